// Run and sweep reports: self-contained HTML, steady interval and mean, metrics round trip,
// the report without gnuplot, a plant still filling, the report in headless Chromium, the 3D view
// (drawn in headless Chromium, or a note without three.js), the drives of belts, pulleys and
// buckets against closed forms, sweep ranking.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "chute_liner_case.h"
#include "case/liner_materials.h"
#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "equipment.h"
#include "output/run.h"
#include "render/render.h"
#include "report/report.h"
#include "report/report_analysis.h"
#include "report/report_wear.h"
#include "pages/viewer3d.h"

extern "C" char** environ;

namespace dem::test {
namespace {

namespace fs = std::filesystem;

// A flat two-triangle liner, an inlet of 2 kg/s and one outlet (tests/chute_liner_case.h).
const std::string kCase = chute_liner_case("report test chute");

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool gnuplot_installed() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':'))
    if (!dir.empty() && fs::exists(fs::path(dir) / "gnuplot")) return true;
  return false;
}

/// The page without the contents of its <script> elements (the inlined three.js names XML
/// namespaces such as http://www.w3.org/1999/xhtml; it fetches nothing).
std::string without_scripts(const std::string& html) {
  std::string out;
  std::size_t from = 0;
  for (std::size_t at = html.find("<script"); at != std::string::npos; at = html.find("<script", from)) {
    const std::size_t open_end = html.find('>', at), close = html.find("</script>", at);
    if (open_end == std::string::npos || close == std::string::npos) break;
    out += html.substr(from, open_end + 1 - from);
    from = close;
  }
  return out + html.substr(from);
}

/// Every <img> embeds its picture as a data URI; nothing refers outside the file: the only
/// scripts are inline (no src), and no address appears outside them.
void expect_self_contained(const std::string& page) {
  const std::string html = without_scripts(page);
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_EQ(html.find("src=\"file"), std::string::npos);
  for (std::size_t at = html.find("<script"); at != std::string::npos; at = html.find("<script", at + 1)) {
    const std::string tag = html.substr(at, html.find('>', at) - at);
    EXPECT_TRUE(tag == "<script" || tag == "<script type=\"application/json\" id=\"v3d-data\"") << tag;
  }
  EXPECT_EQ(html.find("<link"), std::string::npos);
  for (std::size_t at = html.find("<img"); at != std::string::npos; at = html.find("<img", at + 1)) {
    const std::size_t src = html.find("src=\"", at);
    ASSERT_NE(src, std::string::npos);
    EXPECT_EQ(html.compare(src, 16, "src=\"data:image/"), 0) << html.substr(at, 80);
  }
}

struct Fixture {
  fs::path dir;
  Model model;
  State state;
  report::RunReportInput input;

  explicit Fixture(const std::string& name) : dir(fs::temp_directory_path() / name), model(compile(parse_case_text(kCase, "report.yaml"))) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    // Final state: the liner's records, accumulated from t = 1 s to 4 s.
    state.time = 4.0;
    TriangleRecords records;
    records.normal_impulse = {1, 2};
    records.shear_impulse = {1, 2};
    records.shear_work = {30, 120};   // [J] -> 20 and 80 W/m^2 over 3 s on 0.5 m^2
    records.impacts = {5, 6};
    records.impact_energy = {1.5, 3};
    state.records.push_back(records);

    // Rows: outflow rises to 2 kg/s (7.2 t/h) with time constant 0.3 s, noisy; the drive
    // power rises to 50 W.
    std::mt19937_64 random(42);
    std::normal_distribution<double> gauss(0.0, 1.0);
    double out = 0;
    for (int i = 0; i <= 400; ++i) {
      Scalars r;
      r.time = 0.01 * i;
      r.step = i * 100;
      const double q = 2.0 * (1 - std::exp(-r.time / 0.3));
      if (i > 0) out += std::max(0.0, q + 0.2 * gauss(random)) * 0.01;
      r.inserted_mass = 2.0 * r.time + 0.5;
      r.removed_mass = out;
      r.outlet_mass = {out};
      r.particles = static_cast<std::size_t>(100 * (r.inserted_mass - out));
      r.kinetic_translation = 3 + 0.1 * gauss(random);
      r.kinetic_rotation = 0.3;
      r.contacts = 200;
      r.max_overlap_ratio = 0.01;
      r.mean_overlap_ratio = 0.002;
      r.mesh_force = {100};
      r.mesh_power = {50 * (1 - std::exp(-r.time / 0.3)) + 2 * gauss(random)};
      r.mesh_torque = {10 + gauss(random)};
      SensorReading plane;
      plane.flow = q + 0.2 * gauss(random);
      SensorReading box;
      box.mass = 5, box.vx = 2.0, box.vy = 0.05, box.vz = -1.5, box.offset = 0.01 + 0.002 * gauss(random);
      r.sensors = {plane, box};
      input.scalars.push_back(r);
    }
    SensorSpec plane;
    plane.kind = SensorSpec::Kind::plane;
    plane.name = "chute_exit";
    SensorSpec box;
    box.kind = SensorSpec::Kind::box;
    box.name = "receiving_belt_load";
    box.region_min = Vec3(0, -0.5, 0), box.region_max = Vec3(1, 0.5, 0.2);  // 1 m wide along y
    input.sensors = {plane, box};
    input.design = {{"design_capacity_t_h", 7.2}, {"receiving_belt_speed_m_s", 2.5}, {"feed_belt_speed_m_s", 1.5}};
    input.model = &model;
    input.state = &state;
    input.case_path = "cases/report.yaml";
    input.case_text = kCase + "# see https://example.org <b>not bold</b>\n";
    input.version = "test";
    input.wall_seconds = 12.5;
    input.records_from = 1.0;
    input.wear_coefficient = {{"chute_liner", 1e-13}};
    // A caller's image (any bytes: the report embeds, it does not decode).
    const fs::path image = dir / "flow.png";
    std::ofstream(image, std::ios::binary) << "\x89PNG\r\n\x1a\nnot really a picture";
    input.images = {{"Flow at the end", image.string(), "particles coloured by speed"}};
  }
};

// Without a liner the report says how to give one instead of showing no depth.
TEST(RunReport, WithoutAWearCoefficientSaysHowToGiveOne) {
  Fixture f("demdesign_report_no_wear_test");
  f.input.wear_coefficient.clear();
  const fs::path out = f.dir / "report";
  const report::RunMetrics metrics = report::write_run_report(f.input, out.string());
  const std::string html = read(out / "report.html");
  EXPECT_NE(html.find("No wear depth: the case gives no liner. Add <code>wear: {liners: {default: {material: ar400, thickness_mm: 20}}}</code>"),
            std::string::npos);
  EXPECT_EQ(html.find("<h3>Liner life</h3>"), std::string::npos) << "no liner, no life";
  EXPECT_NE(html.find("<td>not given</td>"), std::string::npos);
  EXPECT_TRUE(std::isnan(metrics.get("wear_rate_max_mm_yr"))) << "no wear rate without a coefficient";
  EXPECT_GT(metrics.get("shear_power_max_W_m2"), 0) << "the wear input is still there";
}

// ---- liner life ----------------------------------------------------------------------------

// The arithmetic of liner life against a hand calculation: friction work W_f = 120 J and impact
// energy E = 3 J on a triangle of A = 0.5 m^2 over T = 3 s, a liner 20 mm thick with
// k_s = 4.4e-13 and K_i = 2.8e-12 m^3/J, 4000 h of operation a year, 7.2 t/h conveyed.
TEST(LinerLife, ClosedFormDepthRateLifeAndWearPerMegatonne) {
  const double k_s = 4.4e-13, k_i = 2.8e-12, work = 120, energy = 3, area = 0.5, interval = 3;  // [m^3/J], [J], [m^2], [s]
  const double hours = 4000, thickness = 0.02, throughput = 7.2;                                 // [h], [m], [t/h]
  // Depth rates k W / (A T): 3.52e-11 m/s by sliding, 5.6e-12 m/s by impact.
  const double sliding = report::depth_rate(k_s, work, area, interval), impact = report::depth_rate(k_i, energy, area, interval);
  EXPECT_NEAR(sliding, 3.52e-11, 1e-24);
  EXPECT_NEAR(impact, 5.6e-12, 1e-25);
  const double rate = report::total_rate(sliding, impact);
  EXPECT_NEAR(rate, 4.08e-11, 1e-24);
  // A year of 4000 h is 1.44e7 s: 0.50688 + 0.08064 = 0.58752 mm/yr.
  EXPECT_NEAR(report::mm_per_year(sliding, hours), 0.50688, 1e-12);
  EXPECT_NEAR(report::mm_per_year(impact, hours), 0.08064, 1e-12);
  EXPECT_NEAR(report::mm_per_year(rate, hours), 0.58752, 1e-12);
  // Life: 20 mm / 0.58752 mm/yr = 34.04 years = 408.5 months.
  EXPECT_NEAR(report::life_months(thickness, rate, hours), 12 * 20 / 0.58752, 1e-9);
  // Per million tonnes: 7.2 t/h = 0.002 t/s, so 2.04e-8 m a tonne = 20.4 mm/Mt; times the
  // 0.0288 Mt a year at 4000 h it is the depth a year again.
  const double per_megatonne = report::mm_per_megatonne(rate, throughput);
  EXPECT_NEAR(per_megatonne, 20.4, 1e-9);
  EXPECT_NEAR(per_megatonne * throughput * hours * 1e-6, report::mm_per_year(rate, hours), 1e-12);
  // What is not given stays unknown; a liner that does not wear lasts for ever.
  EXPECT_TRUE(std::isnan(report::depth_rate(std::nan(""), work, area, interval)));
  EXPECT_DOUBLE_EQ(report::total_rate(sliding, std::nan("")), sliding);
  EXPECT_TRUE(std::isnan(report::total_rate(std::nan(""), std::nan(""))));
  EXPECT_TRUE(std::isnan(report::life_months(0.0, rate, hours))) << "no thickness, no life";
  EXPECT_TRUE(std::isinf(report::life_months(thickness, 0.0, hours)));
  EXPECT_TRUE(std::isnan(report::mm_per_megatonne(rate, std::nan("")))) << "no throughput, no mm/Mt";
  // wear_zone puts them together.
  report::Liner liner;
  liner.thickness = thickness, liner.sliding_coefficient = k_s, liner.impact_coefficient = k_i;
  const report::WearZone zone = report::wear_zone(liner, work, energy, area, interval, hours, throughput);
  EXPECT_DOUBLE_EQ(zone.sliding, sliding);
  EXPECT_DOUBLE_EQ(zone.impact, impact);
  EXPECT_DOUBLE_EQ(zone.life_months, report::life_months(thickness, rate, hours));
  EXPECT_DOUBLE_EQ(zone.mm_per_megatonne, per_megatonne);
}

// The same arithmetic through the report, on the fixture's records: the liner's worst triangle
// (120 J of friction work and 3 J of impact energy on 0.5 m^2 over 3 s) and its mean (150 J and
// 4.5 J on 1 m^2), in metrics.csv, the page and wear_life.csv.
TEST(RunReport, LinerLifeOfTheWorstTriangleAndTheMean) {
  Fixture f("demdesign_report_liner_life_test");
  report::Liner liner;
  liner.material = "ar400", liner.origin = "wear.liners.default", liner.thickness = 0.02;
  liner.sliding_coefficient = 4.4e-13, liner.impact_coefficient = 2.8e-12;
  f.input.liners = {{"chute_liner", liner}};
  f.input.operating_hours_per_year = 4000, f.input.operating_hours_given = true;
  const fs::path out = f.dir / "report";
  const report::RunMetrics metrics = report::write_run_report(f.input, out.string());
  const double year = 4000 * 3600.0;                                        // [s] of operation a year
  const double sliding = 4.4e-13 * 120 / 1.5, impact = 2.8e-12 * 3 / 1.5;  // [m/s]
  EXPECT_NEAR(metrics.get("wear_sliding_chute_liner_mm_yr"), sliding * year * 1e3, 1e-9);
  EXPECT_NEAR(metrics.get("wear_impact_chute_liner_mm_yr"), impact * year * 1e3, 1e-9);
  EXPECT_NEAR(metrics.get("wear_rate_max_mm_yr"), (sliding + impact) * year * 1e3, 1e-9);
  EXPECT_NEAR(metrics.get("liner_life_chute_liner_months"), 12 * 0.02 / ((sliding + impact) * year), 1e-6);
  const double mean = (4.4e-13 * 150 + 2.8e-12 * 4.5) / (1.0 * 3.0);  // [m/s]
  EXPECT_NEAR(metrics.get("liner_life_mean_chute_liner_months"), 12 * 0.02 / (mean * year), 1e-6);
  EXPECT_DOUBLE_EQ(metrics.get("liner_life_min_months"), metrics.get("liner_life_chute_liner_months"));
  const double throughput = metrics.get("throughput_t_h");
  ASSERT_GT(throughput, 1.0);
  EXPECT_NEAR(metrics.get("wear_chute_liner_mm_per_Mt"), (sliding + impact) / (throughput / 3600) * 1e9, 1e-9);
  const std::string html = read(out / "report.html");
  EXPECT_NE(html.find("<h3>Liner life</h3>"), std::string::npos);
  EXPECT_NE(html.find(find_liner_material("ar400")->name), std::string::npos) << "the material and its sources";
  EXPECT_NE(html.find("4000 h of operation a year (<code>wear.operating_hours_per_year</code>)"), std::string::npos);
  const std::string csv = read(out / "wear_life.csv");
  EXPECT_NE(csv.find("\"chute_liner\",worst_spot,1,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\"chute_liner\",mesh_mean,,,,,ar400,20,"), std::string::npos) << csv;
  // Without the hours the report uses the default and says it assumed them.
  Fixture g("demdesign_report_liner_hours_test");
  g.input.liners = f.input.liners;
  const report::RunMetrics assumed = report::write_run_report(g.input, (g.dir / "report").string());
  EXPECT_NE(read(g.dir / "report" / "report.html").find("6000 h of operation a year, assumed</b>"), std::string::npos);
  EXPECT_NEAR(assumed.get("liner_life_chute_liner_months"), metrics.get("liner_life_chute_liner_months") * 4000 / 6000, 1e-6);
}

// A mesh with a surface velocity (a belt, a pulley) takes no default liner, only one given by its
// name; the older `wear_coefficients: {default: K}` likewise.
TEST(LinerLife, BeltsTakeNoDefaultLiner) {
  const std::string text = R"(title: a liner and a belt
simulation: {duration: 1.0}
materials:
  gravel: {density: 2600, youngs_modulus: 5e7, restitution: 0.4, friction: 0.5}
  steel: {density: 7800, youngs_modulus: 2e11, restitution: 0.4, friction: 0.4}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
meshes:
  - {name: liner, material: steel, vertices: [[0, 0, 0], [1, 0, 0], [1, 1, 0]], triangles: [[0, 1, 2]]}
  - {name: belt, material: steel, vertices: [[0, 0, -1], [1, 0, -1], [1, 1, -1]], triangles: [[0, 1, 2]], surface_velocity: {linear: [2, 0, 0]}}
particles:
  - {material: gravel, diameter: 0.01, positions: [[0.5, 0.2, 0.5]]}
)";
  const auto liners = [&text](const std::string& wear) {
    const CaseSpec spec = parse_case_text(text + wear, "belts.yaml");
    return report::liners_for(spec, compile(spec));
  };
  auto l = liners("wear: {liners: {default: {material: ar400, thickness_mm: 20}}}\n");
  ASSERT_EQ(l.count("liner"), 1u);
  EXPECT_EQ(l.at("liner").material, "ar400");
  EXPECT_DOUBLE_EQ(l.at("liner").thickness, 0.02);
  EXPECT_DOUBLE_EQ(l.at("liner").sliding_coefficient, find_liner_material("ar400")->sliding_coefficient);
  EXPECT_DOUBLE_EQ(l.at("liner").impact_coefficient, find_liner_material("ar400")->impact_coefficient);
  EXPECT_EQ(l.count("belt"), 0u) << "a belt takes no default";
  l = liners("wear: {liners: {default: {material: ar400, thickness_mm: 20}, belt: {material: rubber, thickness_mm: 10, impact_coefficient: 1.0e-13}}}\n");
  ASSERT_EQ(l.count("belt"), 1u) << "a belt named has its liner";
  EXPECT_EQ(l.at("belt").material, "rubber");
  EXPECT_EQ(l.at("belt").origin, "wear.liners.belt");
  EXPECT_DOUBLE_EQ(l.at("belt").impact_coefficient, 1.0e-13) << "the case's value replaces the table's";
  EXPECT_DOUBLE_EQ(l.at("belt").sliding_coefficient, find_liner_material("rubber")->sliding_coefficient);
  l = liners("wear_coefficients: {default: 1.0e-13}\n");
  EXPECT_EQ(l.count("belt"), 0u) << "nor the older default";
  ASSERT_EQ(l.count("liner"), 1u);
  EXPECT_DOUBLE_EQ(l.at("liner").sliding_coefficient, 1.0e-13);
  EXPECT_TRUE(std::isnan(l.at("liner").impact_coefficient));
  EXPECT_DOUBLE_EQ(l.at("liner").thickness, 0.0) << "no thickness, no life";
}

// Bad wear input is refused naming the file, the line, the key and what is valid.
TEST(LinerLife, BadInputNamesTheKey) {
  const auto error_of = [](const std::string& wear) {
    try {
      (void)compile(parse_case_text(kCase + wear, "wear.yaml"));
    } catch (const CaseError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string hours = error_of("wear: {operating_hours_per_year: 9000}\n");
  EXPECT_EQ(hours.rfind("wear.yaml:", 0), 0u) << hours;
  EXPECT_NE(hours.find("wear.operating_hours_per_year: 9000 h is out of range; valid: [1, 8784] h"), std::string::npos) << hours;
  const std::string thickness = error_of("wear: {liners: {chute_liner: {material: ar400, thickness_mm: -5}}}\n");
  EXPECT_EQ(thickness.rfind("wear.yaml:", 0), 0u) << thickness;
  EXPECT_NE(thickness.find("wear.liners.chute_liner.thickness_mm: -5 mm is out of range; valid: [0.1, 1000] mm"), std::string::npos)
      << thickness;
  const std::string material = error_of("wear: {liners: {default: {material: ar450, thickness_mm: 20}}}\n");
  EXPECT_NE(material.find("wear.liners.default.material: 'ar450' is not valid (did you mean 'ar400'?)"), std::string::npos) << material;
  EXPECT_NE(material.find("mild_steel, ar400, ar500, alumina, rubber, uhmwpe"), std::string::npos) << material;
  const std::string missing = error_of("wear: {liners: {default: {material: ar400}}}\n");
  EXPECT_NE(missing.find("wear.liners.default.thickness_mm: missing"), std::string::npos) << missing;
  const std::string mesh = error_of("wear: {liners: {chute_lienr: {material: ar400, thickness_mm: 20}}}\n");
  EXPECT_NE(mesh.find("wear.liners.chute_lienr: no mesh is named 'chute_lienr' (did you mean 'chute_liner'?)"), std::string::npos) << mesh;
  const std::string twice = error_of("wear_coefficients: {default: 1.0e-13}\nwear: {liners: {default: {material: ar400, thickness_mm: 20}}}\n");
  EXPECT_NE(twice.find("wear_coefficients.default: 'default' also has a liner in wear.liners"), std::string::npos) << twice;
  EXPECT_EQ(error_of("wear: {operating_hours_per_year: 8784, liners: {chute_liner: {material: uhmwpe, thickness_mm: 0.1}}}\n"), "no error")
      << "the bounds themselves are valid";
}

TEST(RunReport, AStoppedRunSaysWhyAboveEverything) {
  Fixture f("demdesign_report_stopped_test");
  f.input.stopped = "numerical trouble: t = 3.5 s: particles 4 and 9 overlap by 60 % of the smaller radius";
  const fs::path out = f.dir / "report";
  report::write_run_report(f.input, out.string());
  const std::string html = read(out / "report.html");
  const auto banner = html.find("The run stopped before its end, at t = ");
  ASSERT_NE(banner, std::string::npos);
  EXPECT_NE(html.find("particles 4 and 9 overlap by 60 %", banner), std::string::npos);
  EXPECT_LT(banner, html.find("<h2")) << "the banner comes before the first section";
  Fixture g("demdesign_report_not_stopped_test");
  report::write_run_report(g.input, (g.dir / "report").string());
  EXPECT_EQ(read(g.dir / "report" / "report.html").find("stopped before its end"), std::string::npos);
}

TEST(RunReport, SelfContainedWithSteadyIntervalMeanAndFiles) {
  Fixture f("demdesign_report_test");
  const fs::path out = f.dir / "report";
  const report::RunMetrics metrics = report::write_run_report(f.input, out.string());

  ASSERT_TRUE(fs::exists(out / "report.html"));
  const std::string html = read(out / "report.html");
  expect_self_contained(html);
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos) << "the caller's image is embedded";
  EXPECT_NE(html.find("&lt;b&gt;not bold&lt;/b&gt;"), std::string::npos) << "case text is escaped";

  // The steady state is detected after the transient, and the mean is the plateau.
  ASSERT_TRUE(metrics.steady) << metrics.steady_text;
  const double from = metrics.get("steady_from_s");
  EXPECT_GT(from, 0.5);
  EXPECT_LT(from, 2.0);
  const double throughput = metrics.get("throughput_t_h");
  EXPECT_NEAR(throughput, 7.2, 0.3);
  EXPECT_NE(html.find(metrics.steady_text), std::string::npos) << metrics.steady_text;
  ASSERT_GE(throughput, 1.0);
  ASSERT_LT(throughput, 10.0);
  EXPECT_NE(html.find(fmt::format("Throughput {:.3f} t/h", throughput)), std::string::npos);
  EXPECT_NEAR(metrics.get("throughput_of_capacity_pct"), 100, 5);
  EXPECT_DOUBLE_EQ(metrics.get("spillage_kg"), 0.0);
  EXPECT_DOUBLE_EQ(metrics.get("blockage"), 0.0);
  EXPECT_NEAR(metrics.get("power_chute_liner_W"), 50, 2);
  // Wear: 120 J over 3 s on 0.5 m^2 = 80 W/m^2; a sliding coefficient of 1e-13 m^3/J alone ->
  // 8e-12 m/s = 0.1728 mm/yr at the default 6000 h of operation a year.
  EXPECT_NEAR(metrics.get("shear_power_max_W_m2"), 80, 1e-9);
  EXPECT_NEAR(metrics.get("wear_rate_max_mm_yr"), 80e-13 * 1000 * kDefaultOperatingHoursPerYear * 3600, 1e-9);
  // Belt loading: 10 mm offset on a 1 m box = 1 %; along speed 2.0 / 2.5 (the receiving belt).
  EXPECT_NEAR(metrics.get("centring_offset_receiving_belt_load_pct"), 1.0, 0.05);
  EXPECT_NEAR(metrics.get("speed_ratio_receiving_belt_load"), 0.8, 1e-9);
  EXPECT_NEAR(metrics.get("vertical_speed_receiving_belt_load_m_s"), -1.5, 1e-9);
  for (const char* section : {"Throughput", "Drives and loads", "Wear", "Belt loading", "Reproducibility", "mass scaling"})
    EXPECT_NE(html.find(section), std::string::npos) << section;
  // The liner does not move: it has loads, no drive and no power row.
  EXPECT_NE(html.find("No mesh moves or has a moving surface: there is no drive."), std::string::npos);
  EXPECT_EQ(html.find("power of chute_liner"), std::string::npos);
  EXPECT_FALSE(fs::exists(out / "drives.csv")) << "no drive, no drives.csv";

  // Files beside the report.
  for (const char* file : {"steady_state.csv", "wear_hotspots.csv", "metrics.csv"}) EXPECT_TRUE(fs::exists(out / file)) << file;
  const std::string hot = read(out / "wear_hotspots.csv");
  EXPECT_NE(hot.find("\n1,chute_liner,1,"), std::string::npos) << hot;
  EXPECT_NE(read(out / "steady_state.csv").find("throughput (intended outlets)"), std::string::npos);
  if (gnuplot_installed()) {
    EXPECT_TRUE(fs::exists(out / "plots" / "outlet_flow.png"));
    EXPECT_TRUE(fs::exists(out / "plots" / "outlet_flow.gp"));
    EXPECT_TRUE(fs::exists(out / "plots" / "outlet_flow.tsv"));
    EXPECT_EQ(html.find("gnuplot not found"), std::string::npos);
  }

  // metrics.csv round trip.
  const report::RunMetrics back = report::read_metrics((out / "metrics.csv").string());
  EXPECT_EQ(back.steady, metrics.steady);
  EXPECT_EQ(back.steady_text, metrics.steady_text);
  ASSERT_EQ(back.values.size(), metrics.values.size());
  for (std::size_t k = 0; k < back.values.size(); ++k) {
    EXPECT_EQ(back.values[k].first, metrics.values[k].first);
    if (std::isnan(metrics.values[k].second))
      EXPECT_TRUE(std::isnan(back.values[k].second)) << back.values[k].first;
    else
      EXPECT_EQ(back.values[k].second, metrics.values[k].second) << back.values[k].first;
  }
  // The standard errors of the means (the third column) come back too, and the throughput has one.
  EXPECT_EQ(back.std_errors, metrics.std_errors);
  EXPECT_GT(back.std_error("throughput_t_h"), 0.0) << "the outlet's throughput is a mean with a batch-means standard error";
  EXPECT_TRUE(std::isnan(back.std_error("spillage_kg"))) << "a total has none";
}

TEST(RunReport, WritesWithoutGnuplotAndSaysSo) {
  Fixture f("demdesign_report_nognuplot_test");
  const fs::path empty = f.dir / "empty_path";
  fs::create_directories(empty);
  const std::string saved = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", empty.c_str(), 1);
  const report::RunMetrics metrics = report::write_run_report(f.input, (f.dir / "report").string());
  setenv("PATH", saved.c_str(), 1);
  const std::string html = read(f.dir / "report" / "report.html");
  EXPECT_NE(html.find("gnuplot not found: install gnuplot-nox for the plots"), std::string::npos);
  expect_self_contained(html);
  EXPECT_TRUE(metrics.steady);
  EXPECT_TRUE(fs::exists(f.dir / "report" / "plots" / "outlet_flow.gp")) << "the script is kept to draw it later";
}

TEST(RunReport, SpillageAndNoSteadyStateAreFlagged) {
  Fixture f("demdesign_report_spill_test");
  // The outflow keeps rising (a ramp), and 1 kg leaves the domain.
  double out = 0;
  for (Scalars& r : f.input.scalars) {
    out = 0.05 * r.time * r.time;
    r.outlet_mass = {out}, r.removed_mass = out, r.lost_mass = r.time > 2 ? 1.0 : 0.0;
  }
  const report::RunMetrics metrics = report::write_run_report(f.input, (f.dir / "report").string());
  EXPECT_FALSE(metrics.steady);
  EXPECT_NE(metrics.steady_text.find("still rising"), std::string::npos) << metrics.steady_text;
  EXPECT_DOUBLE_EQ(metrics.get("spillage_kg"), 1.0);
  const std::string html = read(f.dir / "report" / "report.html");
  EXPECT_NE(html.find("No steady state reached"), std::string::npos);
  EXPECT_NE(html.find("Spillage: 1"), std::string::npos);
}

TEST(RunReport, PlantStillFillingIsNotSteadyEvenWithASteadyOutflow) {
  Fixture f("demdesign_report_filling_test");
  // 2.5 kg/s in, 2 kg/s out: the outflow settles, the hold-up grows by 0.5 kg/s.
  for (Scalars& r : f.input.scalars) r.inserted_mass = 2.5 * r.time + 0.5;
  const report::RunMetrics metrics = report::write_run_report(f.input, (f.dir / "report").string());
  EXPECT_FALSE(metrics.steady);
  EXPECT_NE(metrics.steady_text.find("still filling"), std::string::npos) << metrics.steady_text;
}

/// Runs `argv` without a shell, its standard output and error into `output`; returns the exit
/// status (127 when it cannot be started).
int run_program(std::vector<std::string> argv, const fs::path& output) {
  std::vector<char*> args;
  for (auto& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = 0;
  const int error = posix_spawnp(&pid, args[0], &files, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  if (error != 0) return 127;
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

// The report opens in a real browser (Debian's chromium, headless): a probe page loads it in a
// frame and counts the images that decoded; the browser's console must show no errors.
TEST(RunReport, OpensInHeadlessChromiumWithEveryImageShown) {
  Fixture f("demdesign_report_browser_test");
  f.input.images.clear();  // the fixture's image is not a real PNG; the plots are
  const fs::path out = f.dir / "report";
  report::write_run_report(f.input, out.string());
  std::ofstream(f.dir / "probe.html") << R"(<!DOCTYPE html><html><body><pre id="result">pending</pre>
<iframe id="report" src="report/report.html" width="1200" height="800"></iframe>
<script>
document.getElementById('report').addEventListener('load', () => {
  const doc = document.getElementById('report').contentDocument;
  const images = [...doc.images];
  const shown = images.filter(i => i.complete && i.naturalWidth > 0).length;
  document.getElementById('result').textContent = 'images ' + shown + '/' + images.length + ' title ' + doc.title;
});
</script></body></html>)";
  const fs::path log = f.dir / "chromium.txt";
  const int status = run_program({"chromium", "--headless", "--no-sandbox", "--disable-gpu", "--allow-file-access-from-files",
                                  "--enable-logging=stderr", "--v=0", "--virtual-time-budget=10000", "--dump-dom",
                                  "file://" + (f.dir / "probe.html").string()},
                                 log);
  ASSERT_NE(status, 127) << "chromium is not installed (Debian package chromium; .ci/install-deps installs it)";
  const std::string text = read(log);
  ASSERT_EQ(status, 0) << text;
  const std::size_t at = text.find("images ");
  ASSERT_NE(at, std::string::npos) << text;
  int shown = 0, total = 0;
  ASSERT_EQ(std::sscanf(text.c_str() + at, "images %d/%d", &shown, &total), 2) << text.substr(at, 80);
  EXPECT_GE(total, gnuplot_installed() ? 5 : 0);
  EXPECT_EQ(shown, total) << "every image must decode";
  EXPECT_NE(text.find("title report test chute"), std::string::npos) << text.substr(at, 200);
  EXPECT_EQ(text.find("Uncaught"), std::string::npos) << text;
  EXPECT_EQ(text.find(":ERROR:CONSOLE"), std::string::npos) << text;
}

bool three_js_installed() { return fs::exists(viewer3d::kDefaultThreeJs); }

TEST(RunReport, ViewerSaysWhyWithoutThreeJs) {
  Fixture f("demdesign_report_nothree_test");
  f.input.viewer.three_js = (f.dir / "absent" / "three.min.js").string();
  report::write_run_report(f.input, (f.dir / "report").string());
  const std::string html = read(f.dir / "report" / "report.html");
  EXPECT_NE(html.find("3D view not available: three.js not found at " + f.input.viewer.three_js), std::string::npos);
  EXPECT_NE(html.find("libjs-three"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  expect_self_contained(html);
}

TEST(RunReport, ViewerInlinesThreeJsAndSubsamplesParticles) {
  if (!three_js_installed()) GTEST_SKIP() << "three.js not installed (Debian package libjs-three; .ci/install-deps installs it)";
  Fixture f("demdesign_report_viewer_data_test");
  for (int k = 0; k < 50; ++k) f.state.add_sphere(0.01 * k, 0.5, 0.1, 0.005, 2600, 0);
  f.input.viewer.max_particles = 20;
  report::write_run_report(f.input, (f.dir / "report").string());
  const std::string html = read(f.dir / "report" / "report.html");
  expect_self_contained(html);
  EXPECT_NE(html.find("three.js (MIT licence), inlined from"), std::string::npos);
  EXPECT_NE(html.find("<b>Subsampled:</b> 20 of the 50 particles are shown"), std::string::npos);
  EXPECT_NE(html.find("\"particles\":{\"n\":20,"), std::string::npos);
  EXPECT_NE(html.find("\"shear\":{\"label\":\"shear work rate\",\"unit\":\"W/m\\u00b2\",\"max\":20,\"peak\":80}"), std::string::npos)
      << "scale to the 99th percentile of the liner's 20 and 80 W/m^2 (the lower), the peak beside it";
}

/// The bounding box of the pixels of `colour` (within 3 per channel) and how many pixels inside
/// it differ from that colour by more than 40 in some channel.
struct ViewerArea {
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
  long background = 0, drawn = 0;
};
ViewerArea viewer_area(const render::Image& image, std::array<int, 3> colour) {
  ViewerArea a;
  auto distance = [&](const std::uint8_t* p) {
    return std::max({std::abs(p[0] - colour[0]), std::abs(p[1] - colour[1]), std::abs(p[2] - colour[2])});
  };
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      if (distance(image.pixel(x, y)) <= 3) a.x0 = std::min(a.x0, x), a.y0 = std::min(a.y0, y), a.x1 = std::max(a.x1, x), a.y1 = std::max(a.y1, y), ++a.background;
  for (int y = a.y0; y <= a.y1; ++y)
    for (int x = a.x0; x <= a.x1; ++x)
      if (distance(image.pixel(x, y)) > 40) ++a.drawn;
  return a;
}

// The main job (cases/transfer_chute.yaml, its first 0.45 s: gravel fed onto the feed belt under
// the hood) reported, then opened in headless Chromium with WebGL on SwiftShader: the view must
// say it drew, the console must show no errors, and a screenshot scrolled to the view must show
// the canvas with walls and particles on its background.
TEST(RunReport, ViewerDrawsInHeadlessChromium) {
  if (!three_js_installed()) GTEST_SKIP() << "three.js not installed (Debian package libjs-three; .ci/install-deps installs it)";
  Fixture f("demdesign_report_viewer_test");
  CaseSpec spec = parse_case_file(std::string(DEMDESIGN_SOURCE_DIR) + "/cases/transfer_chute.yaml");
  equipment::expand_equipment(spec);
  spec.simulation.duration = 0.45;
  const Model model = compile(spec);
  State state = initial_state(model);
  Workspace work;
  RunOptions options;
  options.write_files = false;
  options.progress = false;
  std::ostringstream log;
  const RunSummary summary = run(model, state, work, options, log);
  ASSERT_GT(state.owned(), 100u) << log.str();
  f.input.model = &model, f.input.state = &state, f.input.records_from = 0;
  f.input.images.clear();
  const fs::path out = f.dir / "report";
  report::write_run_report(f.input, out.string());
  const std::string page = "file://" + (out / "report.html").string();

  const fs::path log_path = f.dir / "chromium.txt";
  const std::vector<std::string> common = {"chromium", "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                                           "--enable-logging=stderr", "--v=0", "--hide-scrollbars", "--virtual-time-budget=20000"};
  std::vector<std::string> dom = common;
  dom.insert(dom.end(), {"--dump-dom", page});
  const int status = run_program(dom, log_path);
  ASSERT_NE(status, 127) << "chromium is not installed (Debian package chromium; .ci/install-deps installs it)";
  const std::string text = read(log_path);
  ASSERT_EQ(status, 0) << text;
  EXPECT_NE(text.find("id=\"v3d\" data-state=\"drawn\""), std::string::npos) << text.substr(0, 3000);
  EXPECT_NE(text.find("<div id=\"v3d-msg\" style=\"display:none\"></div>"), std::string::npos) << "the view shows no error";
  EXPECT_EQ(text.find("Uncaught"), std::string::npos) << text.substr(0, 3000);
  EXPECT_EQ(text.find(":ERROR:CONSOLE"), std::string::npos) << text.substr(0, 3000);

  // The screenshot: a probe page holds the report in a frame scrolled to the view.
  std::ofstream(f.dir / "probe.html") << R"(<!DOCTYPE html><html><body style="margin:0">
<iframe id="report" src="report/report.html" style="border:0;width:1200px;height:900px"></iframe>
<script>
document.getElementById('report').addEventListener('load', () => {
  const w = document.getElementById('report').contentWindow;
  w.scrollTo(0, w.document.getElementById('view3d').getBoundingClientRect().top + w.scrollY);
});
</script></body></html>)";
  const fs::path shot = f.dir / "viewer.png";
  std::vector<std::string> screenshot = common;
  screenshot.insert(screenshot.end(), {"--allow-file-access-from-files", "--window-size=1200,900", "--screenshot=" + shot.string(),
                                       "file://" + (f.dir / "probe.html").string()});
  ASSERT_EQ(run_program(screenshot, f.dir / "chromium_screenshot.txt"), 0) << read(f.dir / "chromium_screenshot.txt");
  const render::Image image = render::read_png(shot.string());
  const ViewerArea area = viewer_area(image, {0xec, 0xef, 0xf4});  // the canvas's clear colour
  std::cout << "screenshot: " << shot.string() << " (viewer " << area.x1 - area.x0 + 1 << " x " << area.y1 - area.y0 + 1 << " px, "
            << area.drawn << " drawn pixels)\n";
  ASSERT_GT(area.background, 0) << "no viewer background in " << shot;
  EXPECT_GT(area.x1 - area.x0, 600) << shot;
  EXPECT_GT(area.y1 - area.y0, 300) << shot;
  EXPECT_GT(area.drawn, 2000) << "the canvas shows only its background: " << shot;
}

// ---- drives: belts, pulleys, screws and buckets -------------------------------------------

// The belt's drive numbers from what a run records of it, on synthetic contacts: forces F_i on
// particles at points x_i of an inclined belt whose surface moves at v along d. The run records
// the force on the belt -sum F_i, its torque about the motion origin and the power
// sum F_i . v d; the belt pull F_t times v must give that power exactly.
TEST(Drives, BeltPowerIsPullTimesSpeedOnSyntheticContacts) {
  const double v = 2.5;                                            // [m/s]
  const Eigen::Vector3d d = Eigen::Vector3d(1, 0, 0.2).normalized();  // up a slope of 11.3 deg
  MeshWall belt;
  belt.name = "belt";
  belt.surface_velocity.kind = SurfaceVelocitySpec::Kind::linear;
  belt.surface_velocity.velocity = v * d;
  ASSERT_EQ(report::drive_kind(belt), report::DriveKind::belt);
  const report::DriveGeometry g = report::drive_geometry(belt, 1.0);
  EXPECT_NEAR(g.speed, v, 1e-12);
  EXPECT_NEAR((g.direction - d).norm(), 0.0, 1e-12);
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::Vector3d force(0, 0, 0), torque(0, 0, 0);  // on the belt [N], [N m] about the world origin
  double power = 0;                                 // [W] on the particles
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector3d on_particle(20 * uniform(random), 5 * uniform(random), 100 * (1.5 + uniform(random)));
    const Eigen::Vector3d at = 3 * uniform(random) * d + Eigen::Vector3d(0, 0.4 * uniform(random), 0);
    force -= on_particle, torque += at.cross(-on_particle), power += on_particle.dot(v * d);
  }
  const report::DriveReading r = report::drive_reading(g, {force.x(), force.y(), force.z(), torque.x(), torque.y(), torque.z()});
  EXPECT_DOUBLE_EQ(r.effort, report::belt_pull(force, g.direction));
  EXPECT_NEAR(r.effort, -force.dot(d), 1e-12 * force.norm());
  EXPECT_NEAR(r.check_power, power, 1e-12 * std::abs(power) + 1e-12);
  EXPECT_NEAR(r.effort * v, power, 1e-12 * std::abs(power) + 1e-12);
}

// A force at a known lever: F = (0, 100, 0) N at (2, 0, 0) m. About the world origin its torque
// is 200 N m along z; about an axis through (1, 0, 0) along z it is 100 N m.
TEST(Drives, TorqueAboutTheOwnAxisOfAForceAtAKnownLever) {
  const Eigen::Vector3d force(0, 100, 0), at(2, 0, 0), origin(0, 0, 0), axis(0, 0, 1);
  const Eigen::Vector3d torque = (at - origin).cross(force);
  EXPECT_DOUBLE_EQ(torque.z(), 200.0);
  EXPECT_DOUBLE_EQ(report::torque_about_axis(torque, force, origin, Eigen::Vector3d(1, 0, 0), axis), 100.0);
  EXPECT_DOUBLE_EQ(report::torque_about_axis(torque, force, origin, origin, axis), 200.0);
  EXPECT_DOUBLE_EQ(report::torque_about_axis(torque, force, origin, Eigen::Vector3d(1, 5, -3), axis), 100.0)
      << "any point of the axis";
  // A pulley turning at 3 rad/s about that axis: the material pushes it along its turning, so the
  // shaft torque (positive when the material resists) is -100 N m and the power on the material,
  // F_particle . (omega x (x - p)), -300 W.
  MeshWall pulley;
  pulley.surface_velocity.kind = SurfaceVelocitySpec::Kind::rotation;
  pulley.surface_velocity.axis = axis, pulley.surface_velocity.point = Eigen::Vector3d(1, 0, 0);
  pulley.surface_velocity.angular_speed = 3.0;
  const report::DriveGeometry g = report::drive_geometry(pulley, 0.0);
  ASSERT_EQ(g.kind, report::DriveKind::rotating);
  const report::DriveReading r = report::drive_reading(g, {force.x(), force.y(), force.z(), torque.x(), torque.y(), torque.z()});
  const double power = (-force).dot((3.0 * axis).cross(at - Eigen::Vector3d(1, 0, 0)));
  EXPECT_DOUBLE_EQ(r.effort, -100.0);
  EXPECT_DOUBLE_EQ(power, -300.0);
  EXPECT_DOUBLE_EQ(r.check_power, power);
}

// A screw turning clockwise about a tilted axis through `point` (a rotation motion part): the
// recorded torque is about the motion origin, which is that point; the shaft torque about the
// axis oriented along the turning, times the angular speed, is the power on the material.
TEST(Drives, ShaftTorqueOfAScrewTimesSpeedIsItsPower) {
  MeshWall screw;
  MotionPart turn;
  turn.kind = MotionPart::Kind::rotation;
  turn.axis = Eigen::Vector3d(1, 0, 0.3).normalized(), turn.point = Eigen::Vector3d(0.5, 0, 0.2), turn.angular_speed = -4.0;
  screw.motion.parts.push_back(turn);
  const double t = 0.37;  // [s]
  const report::DriveGeometry g = report::drive_geometry(screw, t);
  ASSERT_EQ(g.kind, report::DriveKind::rotating);
  EXPECT_NEAR((g.direction + turn.axis).norm(), 0.0, 1e-12) << "oriented along the clockwise turning";
  EXPECT_NEAR(g.speed, 4.0, 1e-12);
  EXPECT_NEAR((g.origin - turn.point).norm(), 0.0, 1e-12);
  // Two contacts; the wall's velocity there from the motion itself.
  const RigidVelocity motion = screw.motion.velocity(t);
  const Eigen::Vector3d f1(30, -80, 10), x1(0.7, 0.15, 0.1), f2(-5, 40, 60), x2(1.2, -0.1, 0.5);  // on the screw [N], [m]
  const Eigen::Vector3d force = f1 + f2, torque = (x1 - g.origin).cross(f1) + (x2 - g.origin).cross(f2);
  const double power = -f1.dot(motion.at(x1)) - f2.dot(motion.at(x2));
  const report::DriveReading r = report::drive_reading(g, {force.x(), force.y(), force.z(), torque.x(), torque.y(), torque.z()});
  EXPECT_NEAR(r.check_power, power, 1e-12 * (std::abs(power) + 1));
  EXPECT_NEAR(r.effort, -torque.dot(g.direction), 1e-12);
}

// The meshes of a run with a belt, a pulley, a static liner and two buckets on one belt loop.
const char* kDrivesCase = R"(title: drives test
simulation: {duration: 4.0}
materials:
  gravel: {density: 2600, youngs_modulus: 5e7, restitution: 0.4, friction: 0.5}
  rubber: {density: 1200, youngs_modulus: 1e7, restitution: 0.4, friction: 0.6}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
meshes:
  - name: belt
    material: rubber
    vertices: [[-2, -0.5, 0], [0, -0.5, 0], [0, 0.5, 0], [-2, 0.5, 0]]
    triangles: [[0, 1, 2], [0, 2, 3]]
    surface_velocity: {linear: [2.0, 0, 0]}
  - name: pulley
    material: rubber
    vertices: [[0, -0.5, 0], [0.2, -0.5, -0.2], [0, 0.5, 0]]
    triangles: [[0, 1, 2]]
    surface_velocity: {rotation: {axis: [0, 1, 0], point: [0, 0, -0.2], rad_per_s: 10}}
  - name: liner
    material: rubber
    vertices: [[0, 0, 1], [1, 0, 1], [1, 1, 1]]
    triangles: [[0, 1, 2]]
  - name: bucket_a
    material: rubber
    vertices: [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]]
    triangles: [[0, 1, 2]]
    motion: {belt_loop: {axis: [0, 1, 0], lower: [3, 0, 0], upper: [3, 0, 10], radius: 0.3, speed: 1.5}}
  - name: bucket_b
    material: rubber
    vertices: [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]]
    triangles: [[0, 1, 2]]
    motion: {belt_loop: {axis: [0, 1, 0], lower: [3, 0, 0], upper: [3, 0, 10], radius: 0.3, speed: 1.5, offset: 1.0}}
particles:
  - {material: gravel, diameter: 0.01, positions: [[-1, 0, 0.5]]}
)";

/// Rows of a run with kDrivesCase's meshes: the belt dragged back by 300 N (noisy) under 2 kN of
/// weight, the pulley pushed down and back at a point of its surface behind its top, the liner
/// loaded by 100 N, each bucket dragged back along its path by 40 N.
std::vector<Scalars> drives_rows(const Model& model) {
  std::mt19937_64 random(11);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Eigen::Vector3d axis_point(0, 0, -0.2), axis(0, 1, 0), contact(-0.1, 0.0, -0.2 + std::sqrt(0.03));  // pulley [m]
  std::vector<Scalars> rows;
  for (int i = 0; i <= 400; ++i) {
    Scalars r;
    r.time = 0.01 * i;
    r.kinetic_translation = 3 + 0.1 * gauss(random);
    const Eigen::Vector3d belt(-300 + 20 * gauss(random), 5 * gauss(random), -2000 + 50 * gauss(random));
    const Eigen::Vector3d pulley(-50 + 5 * gauss(random), 0, -500);
    const Eigen::Vector3d liner(0, 0, -100), liner_at(0.5, 0.5, 1);
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> loads = {
        {belt, Eigen::Vector3d(-1, 0, 0).cross(belt)}, {pulley, contact.cross(pulley)}, {liner, liner_at.cross(liner)}};
    r.mesh_power = {-belt.x() * 2.0, -pulley.dot((10.0 * axis).cross(contact - axis_point)), 0.0};
    for (std::size_t m = 3; m < model.meshes.size(); ++m) {
      const RigidVelocity v = model.meshes[m].motion.velocity(r.time);
      const Eigen::Vector3d on_bucket = -40.0 * v.linear.normalized();
      loads.push_back({on_bucket, Eigen::Vector3d::Zero()});
      r.mesh_power.push_back(-on_bucket.dot(v.linear));
    }
    for (const auto& [f, t] : loads) r.mesh_load.push_back({f.x(), f.y(), f.z(), t.x(), t.y(), t.z()}), r.mesh_force.push_back(f.norm());
    r.mesh_torque.assign(model.meshes.size(), 0.0);
    rows.push_back(std::move(r));
  }
  return rows;
}

// The drives table: a belt's pull and power with F_t v beside it, a pulley's shaft torque about its
// own axis with T omega beside it, the buckets of one loop as one drive, a static liner in the
// loads only; each a mean over the steady state with its standard error.
TEST(RunReport, DrivesTableGivesPullTorqueAndPowerOfEachMovingPartOnly) {
  const fs::path dir = fs::temp_directory_path() / "demdesign_report_drives_test";
  fs::remove_all(dir);
  const Model model = compile(parse_case_text(kDrivesCase, "drives.yaml"));
  State state;
  state.time = 4.0;
  report::RunReportInput input;
  input.model = &model, input.state = &state, input.scalars = drives_rows(model), input.version = "test";
  const report::RunAnalysis run = report::analyse_run(input);
  ASSERT_TRUE(run.steady) << run.metrics.steady_text;
  ASSERT_EQ(run.drives.size(), 3u) << "belt, pulley, and the two buckets as one";
  const report::Drive& belt = run.drives[0];
  EXPECT_EQ(belt.kind, report::DriveKind::belt);
  EXPECT_NEAR(belt.speed, 2.0, 1e-12);
  EXPECT_NEAR(belt.effort.at_run.mean, 300, 5);
  EXPECT_GT(belt.effort.at_run.std_error, 0);
  EXPECT_LT(belt.effort.at_run.std_error, 5);
  EXPECT_NEAR(belt.power.at_run.mean, 600, 10);
  for (std::size_t i = 0; i < run.t.size(); ++i) EXPECT_NEAR(belt.check.y[i], belt.power.y[i], 1e-9) << "row " << i;
  // The pulley: -((contact - axis point) x F) . y = 58.7 N m, resisting (about the world origin
  // the same force has 48.7 N m).
  const report::Drive& pulley = run.drives[1];
  const Eigen::Vector3d lever = Eigen::Vector3d(-0.1, 0.0, -0.2 + std::sqrt(0.03)) - Eigen::Vector3d(0, 0, -0.2);
  const double expected = -lever.cross(Eigen::Vector3d(-50, 0, -500)).y();  // [N m]
  EXPECT_EQ(pulley.kind, report::DriveKind::rotating);
  EXPECT_GT(expected, 0) << "pushed back: the material resists";
  EXPECT_NEAR(pulley.effort.at_run.mean, expected, 0.02 * expected);
  EXPECT_NEAR(pulley.check.at_run.mean, pulley.power.at_run.mean, 1e-9 * std::abs(pulley.power.at_run.mean));
  EXPECT_NEAR(pulley.speed, 10.0, 1e-12);
  // The buckets: one chain, 2 x 40 N along the path.
  const report::Drive& chain = run.drives[2];
  EXPECT_EQ(chain.kind, report::DriveKind::path);
  EXPECT_EQ(chain.name, "bucket_a to bucket_b");
  EXPECT_EQ(chain.meshes.size(), 2u);
  EXPECT_NEAR(chain.effort.at_run.mean, 80, 1e-9);
  EXPECT_NEAR(chain.power.at_run.mean, 80 * 1.5, 1e-6);
  EXPECT_NEAR(chain.speed, 1.5, 1e-12);
  EXPECT_EQ(run.mesh_kind[2], report::DriveKind::fixed);

  const report::RunMetrics metrics = report::write_run_report(input, (dir / "report").string());
  EXPECT_NEAR(metrics.get("drive_belt_pull_N"), 300, 5);
  EXPECT_NEAR(metrics.get("drive_belt_power_W"), 600, 10);
  EXPECT_NEAR(metrics.get("drive_pulley_torque_N_m"), expected, 0.02 * expected);
  EXPECT_NEAR(metrics.get("drive_bucket_a_to_bucket_b_pull_N"), 80, 1e-9);
  EXPECT_TRUE(std::isnan(metrics.get("torque_pulley_N_m"))) << "no torque about the world origin";
  const std::string html = read(dir / "report" / "report.html");
  for (const char* text : {"Belts and parts carried on a path", "Rotating parts", "drive power of belt", "drive power of pulley",
                           "2 meshes carried round one belt loop", "Loads on the meshes"})
    EXPECT_NE(html.find(text), std::string::npos) << text;
  EXPECT_EQ(html.find("power of liner"), std::string::npos) << "a static part has no power row";
  const std::string csv = read(dir / "report" / "drives.csv");
  EXPECT_NE(csv.find("\"belt\",belt,pull,N,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\"pulley\",rotating_part,shaft_torque,N m,"), std::string::npos) << csv;
  EXPECT_EQ(csv.find("liner"), std::string::npos) << csv;
}

TEST(SweepReport, RanksByNormalisedWeightedScore) {
  const fs::path dir = fs::temp_directory_path() / "demdesign_sweep_report_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path image = dir / "a.png";
  std::ofstream(image, std::ios::binary) << "\x89PNG\r\n\x1a\nbytes";

  report::SweepReportInput input;
  input.title = "chute angle sweep";
  input.version = "test";
  auto variant = [&](const std::string& name, double throughput, double power) {
    report::SweepVariant v;
    v.name = name;
    v.parameters = {{"chute.angle_deg", name.substr(1)}};
    v.metrics.values = {{"throughput_t_h", throughput}, {"power_total_W", power}};
    v.metrics.steady = true;
    v.image_path = image.string();
    return v;
  };
  // Throughput (maximise, weight 2) and power (minimise, weight 1):
  //   A: (2 * 1/3 + 1 * 0.75) / 3 = 0.472, B: (2 * 1 + 0) / 3 = 0.667, C: (0 + 1) / 3 = 0.333.
  input.variants = {variant("a50", 100, 50), variant("b55", 120, 80), variant("c60", 90, 40)};
  report::SweepVariant failed = variant("d65", 500, 1);
  failed.ok = false;
  failed.message = "numerical error at t = 0.3 s";
  input.variants.push_back(failed);
  input.criteria = {{"throughput_t_h", true, 2.0}, {"power_total_W", false, 1.0}};

  const std::vector<report::Ranked> ranked = report::rank_variants(input);
  ASSERT_EQ(ranked.size(), 4u);
  EXPECT_EQ(ranked[0].variant, 1u);
  EXPECT_EQ(ranked[1].variant, 0u);
  EXPECT_EQ(ranked[2].variant, 2u);
  EXPECT_EQ(ranked[3].variant, 3u) << "failed variants come last";
  EXPECT_NEAR(ranked[0].score, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(ranked[1].score, (2.0 / 3.0 + 0.75) / 3.0, 1e-12);
  EXPECT_NEAR(ranked[2].score, 1.0 / 3.0, 1e-12);
  EXPECT_TRUE(std::isnan(ranked[3].score));

  report::write_sweep_report(input, dir.string());
  const std::string html = read(dir / "sweep.html");
  expect_self_contained(html);
  EXPECT_LT(html.find("b55"), html.find("a50"));
  EXPECT_LT(html.find("a50"), html.find("c60"));
  EXPECT_NE(html.find("numerical error at t = 0.3 s"), std::string::npos);
  const std::string csv = read(dir / "ranking.csv");
  EXPECT_NE(csv.find("1,\"b55\",ok"), std::string::npos) << csv;
  EXPECT_NE(csv.find("4,\"d65\",failed"), std::string::npos) << csv;
}

}  // namespace
}  // namespace dem::test
