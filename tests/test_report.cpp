// Run and sweep reports: self-contained HTML, steady interval and mean, metrics round trip,
// the report without gnuplot, a plant still filling, the report in headless Chromium, the 3D view
// (drawn in headless Chromium, or a note without three.js), sweep ranking.
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

#include "case/spec.h"
#include "core/model.h"
#include "core/particles.h"
#include "equipment.h"
#include "output/run.h"
#include "render/render.h"
#include "report/report.h"
#include "pages/viewer3d.h"

extern "C" char** environ;

namespace dem::test {
namespace {

namespace fs = std::filesystem;

// A flat two-triangle liner, an inlet of 2 kg/s and one outlet.
const char* kCase = R"(title: report test chute
simulation: {duration: 4.0}
materials:
  gravel: {density: 2600, youngs_modulus: 5e7, restitution: 0.4, friction: 0.5}
  steel: {density: 7800, youngs_modulus: 2e11, restitution: 0.4, friction: 0.4}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
meshes:
  - name: chute_liner
    material: steel
    vertices: [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    triangles: [[0, 1, 2], [0, 2, 3]]
inlets:
  - {name: feed, material: gravel, diameter: 0.01, mass_rate_kgs: 2.0, region: {min: [0, 0, 0.5], max: [0.5, 0.5, 0.8]}}
outlets:
  - {name: bin, region: {min: [-1, -1, -2], max: [2, 2, -0.5]}}
)";

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
    input.case_text = std::string(kCase) + "# see https://example.org <b>not bold</b>\n";
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

// Without a specific wear rate the report says how to give one instead of showing no depth.
TEST(RunReport, WithoutAWearCoefficientSaysHowToGiveOne) {
  Fixture f("demdesign_report_no_wear_test");
  f.input.wear_coefficient.clear();
  const fs::path out = f.dir / "report";
  const report::RunMetrics metrics = report::write_run_report(f.input, out.string());
  const std::string html = read(out / "report.html");
  EXPECT_NE(html.find("No wear depth: the case gives no specific wear rate. Add <code>wear_coefficients: {default: K}</code>"), std::string::npos);
  EXPECT_NE(html.find("<td>not given</td>"), std::string::npos);
  EXPECT_TRUE(std::isnan(metrics.get("wear_rate_max_mm_yr"))) << "no wear rate without a coefficient";
  EXPECT_GT(metrics.get("shear_power_max_W_m2"), 0) << "the wear input is still there";
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
  // Wear: 120 J over 3 s on 0.5 m^2 = 80 W/m^2; Archard 1e-13 m^3/J -> 8e-12 m/s = 0.252 mm/yr.
  EXPECT_NEAR(metrics.get("shear_power_max_W_m2"), 80, 1e-9);
  EXPECT_NEAR(metrics.get("wear_rate_max_mm_yr"), 80e-13 * 1000 * 8760 * 3600, 1e-9);
  // Belt loading: 10 mm offset on a 1 m box = 1 %; along speed 2.0 / 2.5 (the receiving belt).
  EXPECT_NEAR(metrics.get("centring_offset_receiving_belt_load_pct"), 1.0, 0.05);
  EXPECT_NEAR(metrics.get("speed_ratio_receiving_belt_load"), 0.8, 1e-9);
  EXPECT_NEAR(metrics.get("vertical_speed_receiving_belt_load_m_s"), -1.5, 1e-9);
  for (const char* section : {"Throughput", "Power and torque", "Wear", "Belt loading", "Reproducibility", "mass scaling"})
    EXPECT_NE(html.find(section), std::string::npos) << section;

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
