// CEMA belt capacity (app/report/belt_capacity.h): the load cross-section of a belt on three
// equal-length rolls against a published capacity table and a hand calculation, the flat belt
// against its own closed form, capacity = A v rho 3.6, the loading verdicts, CEMA's flowability
// classes, bulk densities stated in material files, and the run report's belts on a synthetic
// run (analysis, metrics, belt_capacity.csv and the page).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>

#include "chute_liner_case.h"
#include "case/spec.h"
#include "core/model.h"
#include "core/state.h"
#include "report/belt_capacity.h"
#include "report/report.h"
#include "report/report_analysis.h"

namespace dem::test {
namespace {

namespace fs = std::filesystem;
constexpr double kInch = 0.0254;                      // [m]
constexpr double kDegree = std::numbers::pi / 180.0;  // [rad]

// ---- the cross-section ------------------------------------------------------------------------

// Capacity table of belts on three equal-length troughing rolls (and flat), volume [m^3/h] at a
// belt speed of 1 m/s (so A = C / 3600 m^2), belt widths in inches, surcharge angles 0 to 30 deg,
// as transcribed in a public GitHub belt-conveyor calculation script (Python, in Portuguese:
// tables rolete_3_20, rolete_3_35, rolete_3_45 and rolete_1_0, used beside CEMA's edge distance
// dp = 0.055 B + 0.9 in). The rows checked, within 3 % (the cross-section meets each within 0.7 %):
//   36 in, 20 deg troughing, 20 deg surcharge: 258 m^3/h -> 0.07167 m^2 (0.771 ft^2)
//   36 in, 35 deg, 20 deg: 328 -> 0.09111 m^2      48 in, 35 deg, 20 deg: 603 -> 0.1675 m^2 (1.803 ft^2)
//   48 in, 20 deg, 20 deg: 476 -> 0.1322 m^2       36 in, 45 deg, 20 deg: 354 -> 0.09833 m^2
//   48 in, 35 deg, 0 deg:  417 -> 0.1158 m^2 (the trapezoid alone)
//   36 in, flat, 20 deg:   125 -> 0.03472 m^2 (the surcharge segment alone)
TEST(BeltCapacity, CrossSectionMatchesTheCapacityTableOfThreeEqualRolls) {
  struct Row {
    double inches, troughing, surcharge, table;  // [in], [deg], [deg], [m^3/h at 1 m/s]
  };
  const Row rows[] = {{36, 20, 20, 258}, {36, 35, 20, 328}, {48, 35, 20, 603}, {48, 20, 20, 476},
                      {36, 45, 20, 354}, {48, 35, 0, 417},  {36, 0, 20, 125}};
  for (const Row& r : rows) {
    const double table_area = r.table / 3600;  // [m^2]
    const report::BeltCrossSection s = report::cema_cross_section(r.inches * kInch, r.troughing, r.surcharge);
    EXPECT_NEAR(s.area, table_area, 0.03 * table_area) << r.inches << " in, " << r.troughing << " deg troughing, " << r.surcharge << " deg surcharge";
  }
}

// The 48 in belt on 35 deg rolls with a 20 deg surcharge by hand, in CEMA's inches: c = 0.055 x 48
// + 0.9 = 3.54 in, usable 48 - 7.08 = 40.92 in, centre roll l = 0.371 x 48 + 0.25 = 18.058 in,
// loaded wing w = (40.92 - 18.058) / 2 = 11.431 in; trapezoid (l + w cos 35) w sin 35 = 179.79 in^2;
// chord l + 2 w cos 35 = 36.785 in; segment chord^2 (theta - sin theta cos theta) / (4 sin^2 theta)
// = 80.03 in^2; A = 259.82 in^2 = 0.16762 m^2 = 1.804 ft^2.
TEST(BeltCapacity, CrossSectionPartsByHand) {
  const double in2 = kInch * kInch;  // [m^2] a square inch
  const report::BeltCrossSection s = report::cema_cross_section(48 * kInch, 35, 20);
  EXPECT_NEAR(s.edge_distance / kInch, 3.54, 1e-9);
  EXPECT_NEAR(s.usable_width / kInch, 40.92, 1e-9);
  EXPECT_NEAR(s.centre_roll / kInch, 18.058, 1e-9);
  EXPECT_NEAR(s.wing_load / kInch, 11.431, 1e-9);
  EXPECT_NEAR(s.chord / kInch, 36.7855, 1e-3);
  EXPECT_NEAR(s.trapezoid / in2, 179.792, 1e-2);
  EXPECT_NEAR(s.surcharge / in2, 80.026, 1e-2);
  EXPECT_NEAR(s.area, 0.167624, 1e-6);
  EXPECT_DOUBLE_EQ(s.area, s.trapezoid + s.surcharge);
  // The edge distance is CEMA's 0.055 b + 0.9 in in metres too: 0.0889 m for a 1.2 m belt.
  EXPECT_NEAR(report::cema_edge_distance(1.2), 0.055 * 1.2 + 0.02286, 1e-12);
}

// A flat belt carries the circular segment alone, on a chord of the usable width b - 2c. Its own
// closed form as a sector minus a triangle: radius r = (b - 2c) / (2 sin theta), central angle
// 2 theta, A = r^2 theta - (b - 2c) r cos theta / 2. 0.8 m belt, 20 deg: A = 0.026254 m^2.
TEST(BeltCapacity, FlatBeltIsTheSurchargeSegmentAlone) {
  for (const double width : {0.5, 0.8, 1.2, 2.0}) {
    for (const double surcharge : {5.0, 10.0, 20.0, 30.0}) {
      const report::BeltCrossSection s = report::cema_cross_section(width, 0, surcharge);
      const double usable = width - 2 * (0.055 * width + 0.9 * kInch), theta = surcharge * kDegree;
      const double r = usable / (2 * std::sin(theta));
      EXPECT_NEAR(s.trapezoid, 0, 1e-15);
      EXPECT_NEAR(s.chord, usable, 1e-12);
      EXPECT_NEAR(s.area, r * r * theta - 0.5 * usable * r * std::cos(theta), 1e-12) << width << " m, " << surcharge << " deg";
    }
  }
  EXPECT_NEAR(report::cema_cross_section(0.8, 0, 20).area, 0.026254, 1e-6);
  // No surcharge on a flat belt: no load; troughed, the trapezoid alone.
  EXPECT_DOUBLE_EQ(report::cema_cross_section(0.8, 0, 0).area, 0.0);
  EXPECT_GT(report::cema_cross_section(0.8, 30, 0).area, 0.0);
  // Bad inputs give NaN, not a number that looks like a capacity.
  EXPECT_TRUE(std::isnan(report::cema_cross_section(0, 30, 20).area));
  EXPECT_TRUE(std::isnan(report::cema_cross_section(0.8, std::numeric_limits<double>::quiet_NaN(), 20).area));
  EXPECT_TRUE(std::isnan(report::cema_cross_section(0.8, 30, -5).area));
}

// Capacity = A v rho x 3.6: 0.1 m^2 at 2 m/s of 1500 kg/m^3 is 300 kg/s = 1080 t/h.
TEST(BeltCapacity, CapacityIsAreaSpeedDensityInTonnesPerHour) {
  EXPECT_NEAR(report::belt_capacity_t_h(0.1, 2.0, 1500), 1080, 1e-9);
  // The receiving belt of cases/transfer_chute.yaml: 0.8 m, 30 deg, 20 deg surcharge, 3 m/s, gravel at 1550 kg/m^3.
  const double area = report::cema_cross_section(0.8, 30, 20).area;
  EXPECT_NEAR(area, 0.064355, 1e-6);
  EXPECT_NEAR(report::belt_capacity_t_h(area, 3.0, 1550), area * 3.0 * 1550 * 3.6, 1e-9);
}

// <= 80 % fine, 80-100 % near full, > 100 % overloaded.
TEST(BeltCapacity, VerdictThresholds) {
  using report::LoadingVerdict;
  EXPECT_EQ(report::loading_verdict(0), LoadingVerdict::fine);
  EXPECT_EQ(report::loading_verdict(80), LoadingVerdict::fine);
  EXPECT_EQ(report::loading_verdict(80.001), LoadingVerdict::near_full);
  EXPECT_EQ(report::loading_verdict(100), LoadingVerdict::near_full);
  EXPECT_EQ(report::loading_verdict(100.001), LoadingVerdict::overloaded);
  EXPECT_EQ(report::loading_verdict(std::numeric_limits<double>::quiet_NaN()), LoadingVerdict::unknown);
  EXPECT_STREQ(report::loading_verdict_text(LoadingVerdict::overloaded), "overloaded: spillage expected");
  EXPECT_STREQ(report::loading_verdict_text(LoadingVerdict::near_full), "near full");
}

// CEMA's surcharge angle by angle of repose; without one, the average-flowing class's 20 deg.
TEST(BeltCapacity, FlowabilityClassesGiveTheSurchargeAngle) {
  EXPECT_EQ(report::cema_flowability(std::numeric_limits<double>::quiet_NaN()).surcharge, 20);
  EXPECT_EQ(report::cema_flowability(10).surcharge, 5);
  EXPECT_EQ(report::cema_flowability(25).surcharge, 10);
  EXPECT_EQ(report::cema_flowability(30).surcharge, 20);
  EXPECT_EQ(report::cema_flowability(34.9).surcharge, 20);
  EXPECT_EQ(report::cema_flowability(37).surcharge, 25);
  EXPECT_EQ(report::cema_flowability(45).surcharge, 30);
}

// The bulk densities the shipped material files state in their source of `density`.
TEST(BeltCapacity, BulkDensityStatedInAMaterialFile) {
  EXPECT_NEAR(report::stated_bulk_density("Quartz/granite solid density 2.60-2.70 g/cm^3 (mineral handbooks); bulk density then ~1.5-1.6 t/m^3"),
              1550, 1e-9);
  EXPECT_NEAR(report::stated_bulk_density("Solid density of bituminous coal 1.25-1.45 g/cm^3; bulk 0.8-0.9 t/m^3 (CEMA material tables)"), 850, 1e-9);
  EXPECT_NEAR(report::stated_bulk_density("Apparent pellet density 3.6-4.1 g/cm^3, bulk ~2.2 t/m^3 (Lommen et al. 2019)"), 2200, 1e-9);
  EXPECT_NEAR(report::stated_bulk_density("Bulk density 1450 kg/m^3"), 1450, 1e-9);
  EXPECT_TRUE(std::isnan(report::stated_bulk_density("EN 10025 structural steel")));
}

// ---- the run report's belts ---------------------------------------------------------------------

// A flat two-triangle liner, an inlet of 2 kg/s and one outlet (tests/chute_liner_case.h).
const std::string kCase = chute_liner_case("belt capacity test");

/// A run whose outflow rises to 2 kg/s (7.2 t/h) with a load box on the receiving belt, whose
/// design values give its speed 2.5 m/s, width 0.8 m and troughing 30 deg (no belt mesh: the
/// flow onto it is the outlet's).
struct BeltRun {
  Model model = compile(parse_case_text(kCase, "belt_capacity_test.yaml"));
  State state;
  report::RunReportInput input;

  BeltRun() {
    // Final state: the liner's wall records from t = 1 s to 4 s.
    state.time = 4.0;
    TriangleRecords records;
    records.normal_impulse = {1, 2}, records.shear_impulse = {1, 2}, records.shear_work = {30, 120};  // [N s], [N s], [J]
    records.impacts = {5, 6}, records.impact_energy = {1.5, 3};                                       // [-], [J]
    state.records.push_back(records);
    input.records_from = 1.0;
    std::mt19937_64 random(7);
    std::normal_distribution<double> gauss(0.0, 1.0);
    double out = 0;
    for (int i = 0; i <= 400; ++i) {
      Scalars r;
      r.time = 0.01 * i, r.step = i * 100;
      const double q = 2.0 * (1 - std::exp(-r.time / 0.3));  // [kg/s]
      if (i > 0) out += std::max(0.0, q + 0.2 * gauss(random)) * 0.01;
      r.inserted_mass = 2.0 * r.time + 0.5, r.removed_mass = out, r.outlet_mass = {out};
      r.mesh_power = {0.0};
      SensorReading box;
      box.mass = 5, box.vx = 2.0, box.vz = -1.5, box.offset = 0.01;
      r.sensors = {box};
      input.scalars.push_back(r);
    }
    SensorSpec box;
    box.kind = SensorSpec::Kind::box, box.name = "receiving_belt_load";
    box.region_min = Vec3(0, -0.4, 0), box.region_max = Vec3(1, 0.4, 0.3);
    input.sensors = {box};
    input.design = {{"receiving_belt_speed_m_s", 2.5}, {"receiving_belt_width_m", 0.8}, {"receiving_belt_troughing_angle_deg", 30}};
    input.model = &model, input.state = &state;
    input.case_path = "belt_capacity_test.yaml", input.case_text = kCase;
  }
};

// Capacity of the 0.8 m belt at 30 deg with CEMA's assumed 20 deg surcharge, 2.5 m/s and 0.6 x
// 2600 = 1560 kg/m^3 (assumed): A v rho 3.6 = 0.064355 x 2.5 x 1560 x 3.6 = 903.5 t/h; the
// outlet's 7.2 t/h is 0.8 % of it, fine.
TEST(BeltCapacity, ReportGivesEachReceivingBeltItsCapacityAndLoading) {
  BeltRun f;
  const report::RunAnalysis run = report::analyse_run(f.input);
  ASSERT_EQ(run.belts.size(), 1u);
  const report::BeltCapacity& b = run.belts[0];
  ASSERT_TRUE(b.missing.empty()) << b.missing;
  EXPECT_EQ(b.belt, "receiving_belt");
  EXPECT_EQ(b.sensor, "receiving_belt_load");
  EXPECT_DOUBLE_EQ(b.width, 0.8);
  EXPECT_DOUBLE_EQ(b.troughing, 30);
  EXPECT_DOUBLE_EQ(b.surcharge, 20);
  EXPECT_TRUE(b.surcharge_assumed);
  EXPECT_NEAR(b.bulk_density, 1560, 1e-9);
  EXPECT_TRUE(b.bulk_density_assumed) << b.bulk_density_source;
  const double capacity = report::cema_cross_section(0.8, 30, 20).area * 2.5 * 1560 * 3.6;
  EXPECT_NEAR(b.capacity, capacity, 1e-9);
  EXPECT_NEAR(b.capacity, 903.5, 0.5);
  EXPECT_DOUBLE_EQ(b.throughput, run.primary.at_run.mean);
  EXPECT_NEAR(b.throughput, 7.2, 0.3);
  EXPECT_NEAR(b.loading, 100 * b.throughput / capacity, 1e-9);
  EXPECT_EQ(b.verdict, report::LoadingVerdict::fine);
  EXPECT_NEAR(run.metrics.get("belt_capacity_receiving_belt_t_h"), capacity, 1e-9);
  EXPECT_NEAR(run.metrics.get("belt_loading_receiving_belt_percent"), b.loading, 1e-12);

  // belt_capacity.csv beside the other tables, and the section on the page.
  const fs::path dir = fs::temp_directory_path() / "demdesign_belt_capacity_test";
  fs::remove_all(dir);
  report::write_run_report(f.input, dir.string());
  std::ifstream csv(dir / "belt_capacity.csv");
  std::stringstream text;
  text << csv.rdbuf();
  EXPECT_EQ(text.str().rfind("belt,sensor,width_m,", 0), 0u) << text.str();
  EXPECT_NE(text.str().find("\n\"receiving_belt\",\"receiving_belt_load\",0.8,"), std::string::npos) << text.str();
  std::ifstream page(dir / "report.html");
  std::stringstream html;
  html << page.rdbuf();
  EXPECT_NE(html.str().find("<h3>Belt loading against capacity</h3>"), std::string::npos);
  EXPECT_NE(html.str().find("<i>(assumed)</i>"), std::string::npos);
}

// A belt slowed to 5 mm/s carries 7.2 t/h in a load CEMA sizes for 1.8 t/h: overloaded.
TEST(BeltCapacity, ReportFlagsAnOverloadedBelt) {
  BeltRun f;
  f.input.design[0].second = 0.005;  // [m/s]
  const report::RunAnalysis run = report::analyse_run(f.input);
  ASSERT_EQ(run.belts.size(), 1u);
  EXPECT_GT(run.belts[0].loading, 100);
  EXPECT_EQ(run.belts[0].verdict, report::LoadingVerdict::overloaded);
}

// Design values the case states take the place of the defaults: the bulk density and the
// surcharge angle are then not assumed.
TEST(BeltCapacity, StatedBulkDensityAndSurchargeAreNotAssumed) {
  BeltRun f;
  f.input.design.push_back({"bulk_density_kg_m3", 1600});
  f.input.design.push_back({"receiving_belt_surcharge_angle_deg", 10});
  const report::RunAnalysis run = report::analyse_run(f.input);
  ASSERT_EQ(run.belts.size(), 1u);
  const report::BeltCapacity& b = run.belts[0];
  EXPECT_DOUBLE_EQ(b.bulk_density, 1600);
  EXPECT_FALSE(b.bulk_density_assumed);
  EXPECT_DOUBLE_EQ(b.surcharge, 10);
  EXPECT_FALSE(b.surcharge_assumed);
  EXPECT_NEAR(b.capacity, report::cema_cross_section(0.8, 30, 10).area * 2.5 * 1600 * 3.6, 1e-9);
}

// Without a belt width (no design value, no belt mesh) there is no capacity, and the report says
// why instead of writing a number.
TEST(BeltCapacity, NoWidthNoCapacity) {
  BeltRun f;
  f.input.design = {{"receiving_belt_speed_m_s", 2.5}};
  const report::RunAnalysis run = report::analyse_run(f.input);
  ASSERT_EQ(run.belts.size(), 1u);
  EXPECT_NE(run.belts[0].missing.find("no belt width"), std::string::npos) << run.belts[0].missing;
  EXPECT_TRUE(std::isnan(run.metrics.get("belt_capacity_receiving_belt_t_h")));
}

}  // namespace
}  // namespace dem::test
