// Liner wear from one particle, through the whole chain a user runs: a case (inline YAML with
// `wear.liners` and `wear.operating_hours_per_year`) compiled and run by run(), the per-triangle
// wall records it accumulates (from `output.records_from` on), and the run report written from
// them as `demdesign CASE` writes it (app/cli/main.cpp), read back from metrics.csv and
// wear_life.csv. Each figure against a closed form of a single sphere:
//   sliding: a sphere sliding down a triangulated incline, whose friction work grows with the
//            square of time (Archard: depth rate k_s W / (A T));
//   impact:  a sphere dropped onto a triangulated plate, one impact of 1/2 m v^2 (Bitter,
//            normal incidence: depth rate k_i E / (A T)), and its rebounds, a geometric series.
// The engine-level checks of the same records are tests/test_mesh_walls.cpp's; the report's
// arithmetic on made-up records is tests/test_report.cpp's LinerLife tests.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "core/state.h"
#include "core/workspace.h"
#include "output/run.h"
#include "report/report.h"
#include "report/report_wear.h"

namespace dem::test {
namespace {

namespace fs = std::filesystem;

// ---- the bead, the plate's liner and the plant -----------------------------------------------

constexpr double kG = 9.81;                                   // [m/s^2]
constexpr double kRadius = 0.005;                             // [m] a 10 mm bead
constexpr double kMass = 2500 * std::numbers::pi / 6 * 1e-6;  // [kg] rho pi d^3 / 6 = 1.308997e-3
constexpr double kFriction = 0.1;                             // [-] mu, bead and steel alike (mixed: 0.1)
constexpr double kRestitution = 0.5;                          // [-] e, bead and steel alike
/// [m^3/J] The liner's own coefficients, given in the case over AR400's (4.4e-13, 2.8e-12): a few
/// thousand times larger, so that the figures of one small bead read easily (both laws are linear).
constexpr double kSlidingCoefficient = 1.0e-8, kImpactCoefficient = 2.0e-8;
constexpr double kThickness = 0.020;  // [m] of the liner
constexpr double kHours = 5000;       // [h] of operation a year
constexpr double kYear = kHours * 3600;  // [s] of operation a year: 1.8e7
/// [t/h] The design capacity an equipment generator would give, for the depth per million tonnes.
constexpr double kCapacity = 1000;

/// [m/yr -> mm/yr] A depth rate [m/s] in mm a year of kHours: x 1.8e10.
constexpr double mm_a_year(double rate) { return rate * kYear * 1e3; }
/// [months] Until kThickness is worn through at `rate` [m/s]: 12 x 0.02 / (rate x 1.8e7).
constexpr double months(double rate) { return 12 * kThickness / (rate * kYear); }
/// [mm/Mt] Depth at `rate` [m/s] per million tonnes at kCapacity: rate / (1000 / 3600 t/s) x 1e9.
constexpr double mm_per_megatonne(double rate) { return rate / (kCapacity / 3600) * 1e3 * 1e6; }

/// A number as YAML text, exactly (the shortest form that reads back as the same double).
std::string num(double x) { return fmt::format("{}", x); }

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// What both cases share: the two materials (a soft bead, steel plate), the contact law (Hertz,
/// restitution damping, a Coulomb-capped tangential spring, no rolling resistance: a sphere's
/// only torque is its friction's), and the plate's liner with the operating hours.
std::string shared_keys() {
  return "materials:\n"
         "  beads: {density: 2500, youngs_modulus: 1.0e7, poisson_ratio: 0.25, restitution: " + num(kRestitution) +
         ", friction: " + num(kFriction) + "}\n"
         "  steel: {density: 7800, youngs_modulus: 2.0e11, poisson_ratio: 0.3, restitution: " + num(kRestitution) +
         ", friction: " + num(kFriction) + "}\n"
         "contact: {normal: hertz, damping: restitution, tangential: mindlin}\n"
         "wear:\n"
         "  operating_hours_per_year: " + num(kHours) + "\n"
         "  liners: {plate: {material: ar400, thickness_mm: " + num(1e3 * kThickness) + ", sliding_coefficient: " +
         num(kSlidingCoefficient) + ", impact_coefficient: " + num(kImpactCoefficient) + "}}\n";
}

/// The case run as `demdesign CASE` runs it, into `out`, and its report in out/report with the
/// inputs app/cli/main.cpp's write_run_report gives it (records_from, sensors, design values,
/// the liners of `wear.liners`, the operating hours), without the renders; beside them a design
/// capacity, as an equipment generator gives, for the depth per million tonnes. Returns the
/// metrics as metrics.csv has them.
report::RunMetrics run_and_report(const CaseSpec& spec, const Model& model, State& state, const fs::path& out) {
  fs::remove_all(out);
  Workspace work;
  RunOptions options;
  options.output_directory = out.string();
  options.progress = false;
  std::ostringstream log;
  const RunSummary summary = run(model, state, work, options, log);
  EXPECT_TRUE(summary.stopped.empty()) << summary.stopped;

  report::RunReportInput input;
  input.model = &model, input.state = &state, input.scalars = summary.scalars, input.events = summary.events;
  input.case_path = spec.path, input.version = "test";
  input.wall_seconds = summary.wall_seconds;
  input.stopped = summary.stopped;
  input.records_from = model.output.records_from;
  input.sensors = model.sensors, input.design = model.design;
  input.liners = report::liners_for(spec, model);
  input.operating_hours_per_year = spec.wear.operating_hours_per_year;
  input.operating_hours_given = spec.wear.hours_given;
  for (const auto& outlet : spec.outlets)
    if (!outlet.spillage) input.outlet_intended.push_back(outlet.name);
  input.design.emplace_back("design_capacity_t_h", kCapacity);
  report::write_run_report(input, (out / "report").string());
  return report::read_metrics((out / "report" / "metrics.csv").string());
}

/// One row of wear_life.csv: mesh,zone,triangle,x_m,y_m,z_m,liner_material,thickness_mm,
/// sliding_mm_yr,impact_mm_yr,total_mm_yr,life_months,mm_per_Mt,operating_hours_per_year,throughput_t_h.
struct WearLifeRow {
  std::string triangle, material;
  double thickness_mm = 0, sliding_mm_yr = 0, impact_mm_yr = 0, total_mm_yr = 0, life_months = 0, mm_per_megatonne = 0,
         hours = 0, throughput_t_h = 0;
};

/// The row of mesh `mesh` and zone `zone` (worst_spot, mesh_mean), if the file has it.
std::optional<WearLifeRow> wear_life_row(const fs::path& csv, const std::string& mesh, const std::string& zone) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // the header
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    if (cells.size() != 15 || cells[0] != "\"" + mesh + "\"" || cells[1] != zone) continue;
    WearLifeRow row;
    row.triangle = cells[2], row.material = cells[6];
    double* numbers[] = {&row.thickness_mm, &row.sliding_mm_yr, &row.impact_mm_yr, &row.total_mm_yr,
                         &row.life_months,  &row.mm_per_megatonne, &row.hours,      &row.throughput_t_h};
    for (int k = 0; k < 8; ++k) *numbers[k] = std::stod(cells[7 + k]);
    return row;
  }
  return std::nullopt;
}

// ---- sliding down an incline ------------------------------------------------------------------

// The incline: a plate at theta = 30 deg, L = 0.3 m down its fall line by W = 0.1 m across, two
// triangles split by the diagonal from its top left corner (u, v) = (0, -W/2) to its bottom right
// (L, W/2). Triangle 0 = (0, -W/2), (L, -W/2), (L, W/2); triangle 1 = (0, -W/2), (L, W/2), (0, W/2).
constexpr double kCos = std::numbers::sqrt3 / 2, kSin = 0.5;  // of theta = 30 deg
constexpr double kPlateLength = 0.3, kPlateWidth = 0.1;       // [m]
constexpr double kPlateArea = kPlateLength * kPlateWidth;     // [m^2] A = 0.03, each triangle 0.015
constexpr double kStart = 0.1;           // [m] down the fall line where the sphere starts, on v = 0 (triangle 1)
constexpr double kCrossing = 0.15;       // [m] where v = 0 crosses the diagonal into triangle 0: L / 2
constexpr double kRecordsFrom = 0.02;    // [s] t0, after the contact's first fraction of a millisecond
constexpr double kSlideEnd = 0.2;        // [s] t1

/// A point of the incline as YAML: u [m] down its fall line from its top edge (through the
/// origin), v [m] across, w [m] out of it. Fall line d = (cos, 0, -sin), normal n = (sin, 0, cos).
std::string incline_point(double u, double v, double w) {
  return "[" + num(u * kCos + w * kSin) + ", " + num(v) + ", " + num(-u * kSin + w * kCos) + "]";
}

/// [m] Hertz overlap of the sphere resting on the incline, F = m g cos(theta) = 4/3 E* sqrt(R)
/// delta^1.5 with 1/E* = (1 - 0.25^2)/1e7 + (1 - 0.3^2)/2e11 (E* = 1.066615e7 Pa): 4.96e-6 m.
/// Starting there, the sphere starts with no normal transient.
double resting_overlap() {
  const double youngs = 1.0 / ((1 - 0.25 * 0.25) / 1.0e7 + (1 - 0.3 * 0.3) / 2.0e11);  // [Pa]
  return std::pow(3 * kMass * kG * kCos / (4 * youngs * std::sqrt(kRadius)), 2.0 / 3.0);
}

std::string sliding_case() {
  const double half = 0.5 * kPlateWidth;
  return "title: one sphere sliding down a triangulated incline\n"
         "simulation: {duration: " + num(kSlideEnd) + ", time_step: 1.0e-5, gravity: [0, 0, " + num(-kG) + "]}\n" +
         shared_keys() +
         "meshes:\n"
         "  - name: plate\n"
         "    material: steel\n"
         "    vertices: [" + incline_point(0, -half, 0) + ", " + incline_point(kPlateLength, -half, 0) + ", " +
         incline_point(kPlateLength, half, 0) + ", " + incline_point(0, half, 0) + "]\n"
         "    triangles: [[0, 1, 2], [0, 2, 3]]\n"
         "particles:\n"
         "  - {material: beads, diameter: " + num(2 * kRadius) + ", positions: [" +
         incline_point(kStart, 0, kRadius - resting_overlap()) + "]}\n"
         "output: {records_from: " + num(kRecordsFrom) + ", scalars_every: 500}\n";
}

// A solid sphere (I = 0.4 m R^2) starts at rest on the incline at 30 deg with mu = 0.1: since
// tan(30 deg) = 0.577 > 3.5 mu = 0.35 it slides with slip throughout, the friction F = mu m g cos
// both braking the centre and spinning the sphere up:
//   F       = mu m g cos(theta) = 0.1 x 1.308997e-3 x 9.81 x 0.8660254 = 1.112086e-3 N
//   centre  a_c = g (sin - mu cos)      = 9.81 x 0.4133975 = 4.055429 m/s^2
//   spin    R alpha = 2.5 mu g cos      = 2.123927 m/s^2 (alpha = F R / (0.4 m R^2))
//   slip    a_s = a_c - R alpha = g (sin - 3.5 mu cos) = 9.81 x 0.1968911 = 1.931502 m/s^2
// The friction power F v_slip = F a_s t gives, from t0 = 0.02 s to t1 = 0.2 s,
//   W = F a_s (t1^2 - t0^2) / 2 = 1.112086e-3 x 1.931502 x 0.0396 / 2 = 4.253031e-5 J,
// and since v_slip = (a_s / a_c) v_centre, W is F a_s / a_c per metre the centre travels: the
// contact runs from u(t0) = 0.1 + a_c t0^2 / 2 = 0.1008111 m to u(t1) = 0.1811086 m, crossing
// into triangle 0 at u = 0.15 m, so triangle 1 gets (0.15 - 0.1008111) / 0.0802975 = 61.26 % of
// W, 2.605336e-5 J, and triangle 0 the other 1.647695e-5 J. Over T = t1 - t0 = 0.18 s:
//   mesh mean:  k_s W / (A T) = 1e-8 x 4.253031e-5 / (0.03 x 0.18) = 7.875984e-11 m/s
//               = 1.417677 mm/yr at 5000 h; life 12 x 20 / 1.417677 = 169.29 months; 0.2835354 mm/Mt
//   worst (1):  1e-8 x 2.605336e-5 / (0.015 x 0.18) = 9.649394e-11 m/s
//               = 1.736891 mm/yr; life 138.18 months; 0.3473782 mm/Mt; shear power 9.649394e-3 W/m^2
// Tolerance 2 %: the tangential spring of the contact takes a fraction of a millisecond to load up
// to F at the start, while the sphere slips ahead of the closed form, and keeps a little elastic
// energy; a mirror of the contact law integrated alone puts the work 0.4 % above W (both triangles).
// The sphere stays on the plate, touching it throughout: no impact is recorded, crossing the
// diagonal and at every rebuild of the contact lists alike.
TEST(WearSingleParticle, SlidingWearOfASphereSlidingDownAnInclineIsArchardOfItsFrictionWork) {
  const CaseSpec spec = parse_case_text(sliding_case(), "wear_sliding.yaml");
  const Model model = compile(spec);
  State state = initial_state(model);
  const fs::path out = fs::temp_directory_path() / "demdesign_wear_sliding_test";
  const report::RunMetrics metrics = run_and_report(spec, model, state, out);
  ASSERT_EQ(state.size(), 1u);
  ASSERT_NEAR(state.time, kSlideEnd, 1e-9);

  // The closed form.
  const double force = kFriction * kMass * kG * kCos;                   // [N] 1.112086e-3
  const double centre = kG * (kSin - kFriction * kCos);                 // [m/s^2] a_c 4.055429
  const double slip = kG * (kSin - 3.5 * kFriction * kCos);             // [m/s^2] a_s 1.931502
  const double t0 = kRecordsFrom, t1 = kSlideEnd, interval = t1 - t0;   // [s]
  const double work = force * slip * (t1 * t1 - t0 * t0) / 2;           // [J] 4.253031e-5
  const double u0 = kStart + centre * t0 * t0 / 2, u1 = kStart + centre * t1 * t1 / 2;  // [m] 0.1008111, 0.1811086
  const double upper_work = work * (kCrossing - u0) / (u1 - u0);        // [J] 2.605336e-5 on triangle 1
  ASSERT_NEAR(upper_work, 2.605336e-5, 1e-10);
  ASSERT_LT(u1, kPlateLength - kRadius) << "the sphere stays on the plate";

  // The motion at t1 (from the state, not the records): the centre at a_c t1 = 0.8110858 m/s
  // down the slope, the contact point slipping at a_s t1 = 0.3863004 m/s, nothing across.
  const double along = state.vx[0] * kCos - state.vz[0] * kSin;  // [m/s]
  const double lever = kRadius - resting_overlap();              // [m] centre to contact point
  EXPECT_NEAR(along, centre * t1, 0.01 * centre * t1);
  EXPECT_NEAR(along - lever * state.wy[0], slip * t1, 0.01 * slip * t1);
  EXPECT_NEAR(state.vy[0], 0.0, 1e-9);
  EXPECT_NEAR(state.x[0] * kCos - state.z[0] * kSin, u1, 1e-3) << "down the fall line, 0.1811 m";
  EXPECT_NEAR(state.x[0] * kSin + state.z[0] * kCos, kRadius, 0.01 * kRadius) << "on the plate";

  // The records: the friction work over [t0, t1], split at the diagonal; no impact.
  ASSERT_EQ(state.records.size(), 1u);
  const TriangleRecords& records = state.records[0];
  ASSERT_EQ(records.shear_work.size(), 2u);
  EXPECT_NEAR(records.shear_work[0] + records.shear_work[1], work, 0.02 * work);
  EXPECT_NEAR(records.shear_work[1], upper_work, 0.02 * upper_work);
  EXPECT_NEAR(records.shear_work[0], work - upper_work, 0.02 * (work - upper_work));
  EXPECT_EQ(records.impacts[0] + records.impacts[1], 0.0) << "one contact from start to end";
  EXPECT_EQ(records.impact_energy[0] + records.impact_energy[1], 0.0);

  // The report: its worst triangle (1) in metrics.csv, ...
  const double half_area = kPlateArea / 2;                                          // [m^2]
  const double worst_rate = kSlidingCoefficient * upper_work / (half_area * interval);  // [m/s] 9.649394e-11
  const double mean_rate = kSlidingCoefficient * work / (kPlateArea * interval);        // [m/s] 7.875984e-11
  ASSERT_NEAR(mm_a_year(worst_rate), 1.736891, 1e-6);
  ASSERT_NEAR(mm_a_year(mean_rate), 1.417677, 1e-6);
  EXPECT_NEAR(metrics.get("shear_power_max_W_m2"), upper_work / (half_area * interval), 0.02 * upper_work / (half_area * interval));
  EXPECT_NEAR(metrics.get("wear_sliding_plate_mm_yr"), mm_a_year(worst_rate), 0.02 * mm_a_year(worst_rate));
  EXPECT_DOUBLE_EQ(metrics.get("wear_impact_plate_mm_yr"), 0.0) << "no impact recorded";
  EXPECT_NEAR(metrics.get("wear_rate_max_mm_yr"), metrics.get("wear_sliding_plate_mm_yr"), 1e-12);
  EXPECT_NEAR(metrics.get("liner_life_plate_months"), months(worst_rate), 0.02 * months(worst_rate));  // 138.18
  EXPECT_NEAR(metrics.get("liner_life_mean_plate_months"), months(mean_rate), 0.02 * months(mean_rate));  // 169.29
  EXPECT_NEAR(metrics.get("wear_plate_mm_per_Mt"), mm_per_megatonne(worst_rate), 0.02 * mm_per_megatonne(worst_rate));  // 0.3473782
  EXPECT_DOUBLE_EQ(metrics.get("liner_life_min_months"), metrics.get("liner_life_plate_months"));

  // ... and both rows of wear_life.csv.
  const std::optional<WearLifeRow> mean = wear_life_row(out / "report" / "wear_life.csv", "plate", "mesh_mean");
  ASSERT_TRUE(mean.has_value()) << read(out / "report" / "wear_life.csv");
  EXPECT_EQ(mean->material, "ar400");
  EXPECT_DOUBLE_EQ(mean->thickness_mm, 20.0);
  EXPECT_NEAR(mean->sliding_mm_yr, mm_a_year(mean_rate), 0.02 * mm_a_year(mean_rate));  // 1.417677
  EXPECT_DOUBLE_EQ(mean->impact_mm_yr, 0.0);
  EXPECT_DOUBLE_EQ(mean->total_mm_yr, mean->sliding_mm_yr);
  EXPECT_NEAR(mean->life_months, months(mean_rate), 0.02 * months(mean_rate));  // 169.29
  EXPECT_NEAR(mean->life_months * mean->total_mm_yr, 12 * 20.0, 12 * 20.0 * 2e-5) << "life = 12 x 20 mm / depth a year";
  EXPECT_NEAR(mean->mm_per_megatonne, mm_per_megatonne(mean_rate), 0.02 * mm_per_megatonne(mean_rate));  // 0.2835354
  EXPECT_DOUBLE_EQ(mean->hours, kHours);
  EXPECT_DOUBLE_EQ(mean->throughput_t_h, kCapacity);
  const std::optional<WearLifeRow> worst = wear_life_row(out / "report" / "wear_life.csv", "plate", "worst_spot");
  ASSERT_TRUE(worst.has_value());
  EXPECT_EQ(worst->triangle, "1") << "the upper triangle carries 61 % of the work";
  EXPECT_NEAR(worst->sliding_mm_yr, mm_a_year(worst_rate), 0.02 * mm_a_year(worst_rate));  // 1.736891
  EXPECT_NE(read(out / "report" / "report.html").find("<h3>Liner life</h3>"), std::string::npos);
}

// ---- dropped onto a plate ---------------------------------------------------------------------

// A horizontal plate of 0.2 m x 0.2 m at z = 0, A = 0.04 m^2, two triangles split by the diagonal
// y = x; the sphere falls onto triangle 0 (below the diagonal, 35 mm from it), from rest with its
// lowest point kDrop above the plate.
constexpr double kDrop = 0.05;      // [m] h
constexpr double kDropArea = 0.04;  // [m^2] A, each triangle 0.02

std::string drop_case(double duration) {
  return "title: one sphere dropped onto a triangulated plate\n"
         "simulation: {duration: " + num(duration) + ", time_step: 1.0e-5, gravity: [0, 0, " + num(-kG) + "]}\n" +
         shared_keys() +
         "meshes:\n"
         "  - name: plate\n"
         "    material: steel\n"
         "    vertices: [[-0.1, -0.1, 0], [0.1, -0.1, 0], [0.1, 0.1, 0], [-0.1, 0.1, 0]]\n"
         "    triangles: [[0, 1, 2], [0, 2, 3]]\n"
         "particles:\n"
         "  - {material: beads, diameter: " + num(2 * kRadius) + ", positions: [[0.03, -0.02, " + num(kRadius + kDrop) + "]]}\n"
         "output: {scalars_every: 500}\n";
}

// The sphere lands at v = sqrt(2 g h) = sqrt(2 x 9.81 x 0.05) = 0.990454 m/s after 0.1010 s, with
// the impact energy 1/2 m v^2 = m g h = 1.308997e-3 x 9.81 x 0.05 = 6.420630e-4 J (the wall's
// m* is the sphere's mass), rebounds at e v = 0.495 m/s and comes down again after another
// 2 e v / g = 0.101 s, at 0.202 s: the run stops at 0.15 s, in the air, after one impact. Over
// T = 0.15 s:
//   worst (0):  E / (A/2 T) = 6.420630e-4 / (0.02 x 0.15) = 0.2140210 W/m^2; k_i x that
//               = 2e-8 x 0.2140210 = 4.280420e-9 m/s = 77.04756 mm/yr at 5000 h;
//               life 12 x 20 / 77.04756 = 3.114959 months; 15.40951 mm/Mt at 1000 t/h
//   mesh mean:  half of it on 0.04 m^2: 2.140210e-9 m/s = 38.52378 mm/yr; life 6.229918 months
// Tolerance 0.5 %: the contact is found within one step of the plate, when the sphere has fallen
// h plus at most v dt = 1e-5 m (2e-4 of h). No friction works on a straight drop.
TEST(WearSingleParticle, ImpactWearOfOneDropIsBitterOfItsKineticEnergy) {
  constexpr double kEnd = 0.15;  // [s]
  const CaseSpec spec = parse_case_text(drop_case(kEnd), "wear_drop.yaml");
  const Model model = compile(spec);
  State state = initial_state(model);
  const fs::path out = fs::temp_directory_path() / "demdesign_wear_drop_test";
  const report::RunMetrics metrics = run_and_report(spec, model, state, out);
  ASSERT_EQ(state.size(), 1u);
  ASSERT_NEAR(state.time, kEnd, 1e-9);

  const double energy = kMass * kG * kDrop;  // [J] 1/2 m v^2 = 6.420630e-4
  ASSERT_NEAR(energy, 6.420630e-4, 1e-10);
  // First impact at sqrt(2 h / g) = 0.1010 s; the second 2 e v / g = 0.1010 s later, after the end.
  const double fall = std::sqrt(2 * kDrop / kG), flight = 2 * kRestitution * std::sqrt(2 * kG * kDrop) / kG;  // [s]
  ASSERT_LT(fall, kEnd);
  ASSERT_GT(fall + flight, kEnd);

  // The records: one impact, on triangle 0, of 1/2 m v^2; no friction work.
  ASSERT_EQ(state.records.size(), 1u);
  const TriangleRecords& records = state.records[0];
  ASSERT_EQ(records.impacts.size(), 2u);
  EXPECT_EQ(records.impacts[0], 1.0);
  EXPECT_EQ(records.impacts[1], 0.0);
  EXPECT_NEAR(records.impact_energy[0], energy, 0.005 * energy);
  EXPECT_EQ(records.impact_energy[1], 0.0);
  EXPECT_LT(records.shear_work[0] + records.shear_work[1], 1e-9 * energy);
  // In the air after one bounce, with e^2 of the energy (gravity, acting during the 0.9 ms
  // contact as well, takes about 1 % of the rebound's).
  const double speed2 = state.vx[0] * state.vx[0] + state.vy[0] * state.vy[0] + state.vz[0] * state.vz[0];
  EXPECT_GT(state.z[0], kRadius) << "in the air";
  const double after = 0.5 * kMass * speed2 + kMass * kG * (state.z[0] - kRadius);  // [J]
  EXPECT_NEAR(after, kRestitution * kRestitution * energy, 0.03 * kRestitution * kRestitution * energy);

  // The report: the worst triangle (0) in metrics.csv, the mean in wear_life.csv.
  const double interval = kEnd;  // [s] records from t = 0
  const double worst_rate = kImpactCoefficient * energy / (kDropArea / 2 * interval);  // [m/s] 4.280420e-9
  const double mean_rate = kImpactCoefficient * energy / (kDropArea * interval);       // [m/s] 2.140210e-9
  ASSERT_NEAR(mm_a_year(worst_rate), 77.04756, 1e-4);
  ASSERT_NEAR(months(mean_rate), 6.229918, 1e-5);
  EXPECT_NEAR(metrics.get("impact_power_max_W_m2"), energy / (kDropArea / 2 * interval), 0.005 * energy / (kDropArea / 2 * interval));
  EXPECT_NEAR(metrics.get("wear_impact_plate_mm_yr"), mm_a_year(worst_rate), 0.005 * mm_a_year(worst_rate));  // 77.04756
  EXPECT_NEAR(metrics.get("wear_sliding_plate_mm_yr"), 0.0, 1e-9 * mm_a_year(worst_rate));
  EXPECT_NEAR(metrics.get("liner_life_plate_months"), months(worst_rate), 0.005 * months(worst_rate));  // 3.114959
  EXPECT_NEAR(metrics.get("liner_life_mean_plate_months"), months(mean_rate), 0.005 * months(mean_rate));  // 6.229918
  EXPECT_NEAR(metrics.get("wear_plate_mm_per_Mt"), mm_per_megatonne(worst_rate), 0.005 * mm_per_megatonne(worst_rate));  // 15.40951
  const std::optional<WearLifeRow> worst = wear_life_row(out / "report" / "wear_life.csv", "plate", "worst_spot");
  ASSERT_TRUE(worst.has_value()) << read(out / "report" / "wear_life.csv");
  EXPECT_EQ(worst->triangle, "0");
  EXPECT_NEAR(worst->impact_mm_yr, mm_a_year(worst_rate), 0.005 * mm_a_year(worst_rate));
  const std::optional<WearLifeRow> mean = wear_life_row(out / "report" / "wear_life.csv", "plate", "mesh_mean");
  ASSERT_TRUE(mean.has_value());
  EXPECT_NEAR(mean->impact_mm_yr, mm_a_year(mean_rate), 0.005 * mm_a_year(mean_rate));  // 38.52378
  EXPECT_NEAR(mean->sliding_mm_yr, 0.0, 1e-9 * mm_a_year(mean_rate));
  EXPECT_NEAR(mean->life_months, months(mean_rate), 0.005 * months(mean_rate));  // 6.229918
}

// The same drop run on until the sphere lies still: every rebound is a new contact and its
// impact is counted, each with e^2 of the one before, so the impact energy is the geometric
// series E / (1 - e^2) = 6.420630e-4 / 0.75 = 8.560840e-4 J. The bounces take
// 2 e v / (g (1 - e)) = 0.20 s after the first impact at 0.10 s: over T = 0.45 s the mesh mean is
// 2e-8 x 8.560840e-4 / (0.04 x 0.45) = 9.512044e-10 m/s = 17.12168 mm/yr, life 14.01732 months.
// Without the rebounds it would be 25 % less. Tolerance 2 %: gravity acts during each 1 ms
// contact and takes a little from every rebound, more from the later, smaller ones (a mirror of
// the contact law integrated alone counts 7 impacts and 0.6 % less than the series).
TEST(WearSingleParticle, ImpactWearOfTheReboundsIsAGeometricSeries) {
  constexpr double kEnd = 0.45;  // [s]
  const CaseSpec spec = parse_case_text(drop_case(kEnd), "wear_bounces.yaml");
  const Model model = compile(spec);
  State state = initial_state(model);
  const fs::path out = fs::temp_directory_path() / "demdesign_wear_bounces_test";
  const report::RunMetrics metrics = run_and_report(spec, model, state, out);
  ASSERT_EQ(state.size(), 1u);

  const double series = kMass * kG * kDrop / (1 - kRestitution * kRestitution);  // [J] 8.560840e-4
  ASSERT_NEAR(series, 8.560840e-4, 1e-10);
  const TriangleRecords& records = state.records.at(0);
  EXPECT_GE(records.impacts[0], 4.0) << "the rebounds are new contacts";
  EXPECT_EQ(records.impacts[1], 0.0) << "all on the spot it fell on";
  EXPECT_NEAR(records.impact_energy[0], series, 0.02 * series);
  EXPECT_LT(std::abs(state.vz[0]), 1e-3) << "at rest: every bounce was within the run";

  const double mean_rate = kImpactCoefficient * series / (kDropArea * kEnd);  // [m/s] 9.512044e-10
  ASSERT_NEAR(mm_a_year(mean_rate), 17.12168, 1e-4);
  const std::optional<WearLifeRow> mean = wear_life_row(out / "report" / "wear_life.csv", "plate", "mesh_mean");
  ASSERT_TRUE(mean.has_value()) << read(out / "report" / "wear_life.csv");
  EXPECT_NEAR(mean->impact_mm_yr, mm_a_year(mean_rate), 0.02 * mm_a_year(mean_rate));  // 17.12168
  EXPECT_NEAR(mean->life_months, months(mean_rate), 0.02 * months(mean_rate));          // 14.01732
  EXPECT_NEAR(metrics.get("liner_life_mean_plate_months"), months(mean_rate), 0.02 * months(mean_rate));
  EXPECT_NEAR(metrics.get("wear_impact_plate_mm_yr"), 2 * mm_a_year(mean_rate), 0.02 * 2 * mm_a_year(mean_rate))
      << "all on triangle 0, half the area";  // 34.24336
}

}  // namespace
}  // namespace dem::test
