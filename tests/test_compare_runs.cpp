// Two runs compared (app/report/compare_runs.h) from synthetic run folders written here with
// known report tables: B - A, its standard error sqrt(se_A^2 + se_B^2) and z exactly; figures of
// one run only; means without a standard error (metrics.csv); the keys in which the cases as run
// differ; compare.csv and compare.html; and the errors that name a missing folder or table.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "case/spec.h"
#include "report/compare_runs.h"

namespace dem::test {
namespace {

namespace fs = std::filesystem;

void write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

const char* kSteadyHeader = "series,unit,found,t_start_s,t_end_s,mean,std_dev,std_error,trend_per_s,why\n";
const char* kDrivesHeader = "drive,kind,quantity,unit,mean,std_error,std_dev,samples,t_start_s,t_end_s\n";
const char* kLoadsHeader = "mesh,component,unit,mean,std_error,std_dev,samples,t_start_s,t_end_s\n";

/// Run A: throughput 100 +- 3 t/h, a belt pulling 200 +- 10 N, a chute loaded with -1000 +- 20 N,
/// kinetic energy not steady, a contacts series B lacks. steady_state.csv also holds the belt's
/// series with another mean, which drives.csv replaces.
void write_run_a(const fs::path& dir) {
  write(dir / "run_info.yaml", "software: demdesign 0.1.0\ncase: cases/chute.yaml\nrun_id: 0000000000000001\nmodel_hash: 00000000000000aa\n"
                               "time_step_s: 1e-05\nend:\n  completed: true\n  time_s: 4\n  step: 400000\n");
  write(dir / "case.yaml", "simulation: {duration: 4}\nequipment:\n  transfer_chute: {spoon: {radius: 0.8}}\n"
                           "inlets:\n  - {port: feed_belt, material: gravel, mass_rate_tph: 400}\n");
  write(dir / "report" / "steady_state.csv",
        std::string(kSteadyHeader) + "\"throughput (intended outlets)\",t/h,1,1,4,100,9,3,0,\"\"\n"
                                     "\"outlet bin\",t/h,1,1,4,50,4,1,0,\"\"\n"
                                     "\"drive pull belt\",N,1,1,4,999,10,1,0,\"\"\n"
                                     "\"force z on chute\",N,1,1,4,999,10,1,0,\"\"\n"
                                     "\"kinetic energy\",J,0,1,4,20,2,0.5,0.3,\"still rising: +12 % over the last half (2 s to 4 s)\"\n"
                                     "\"contacts\",-,1,1,4,3000,100,20,0,\"\"\n");
  write(dir / "report" / "drives.csv", std::string(kDrivesHeader) + "\"belt\",belt,pull,N,200,10,40,120,1,4\n"
                                                                     "\"belt\",belt,power,W,600,30,90,120,1,4\n");
  write(dir / "report" / "mesh_loads.csv", std::string(kLoadsHeader) + "chute,fz,N,-1000,20,80,120,1,4\n");
  write(dir / "report" / "metrics.csv", "name,value\nsteady,1\n# steady_text: steady from 1 s to 4 s (throughput (intended outlets))\n"
                                        "throughput_t_h,100\npower_total_W,600\ndrive_screw_torque_N_m,12\nliner_life_min_months,18\n");
}

/// Run B: throughput 110 +- 4 t/h (z = 10 / 5 = 2), the outlet within noise, the belt pulling
/// 150 +- 10 N, a spill outlet A lacks; another spoon radius and model hash, a `wear:` section A
/// lacks, and the duration written as 4.0.
void write_run_b(const fs::path& dir) {
  write(dir / "run_info.yaml", "software: demdesign 0.1.0\ncase: cases/chute.yaml\nrun_id: 0000000000000002\nmodel_hash: 00000000000000bb\n"
                               "time_step_s: 1e-05\nend:\n  completed: true\n  time_s: 4\n  step: 400000\n");
  write(dir / "case.yaml", "# v01 of cases/chute.yaml: spoon.radius=1.0\nsimulation: {duration: 4.0}\nequipment:\n"
                           "  transfer_chute: {spoon: {radius: 1.0}}\ninlets:\n  - {port: feed_belt, material: gravel, mass_rate_tph: 400}\n"
                           "wear: {operating_hours_per_year: 5000}\n");
  write(dir / "report" / "steady_state.csv", std::string(kSteadyHeader) + "\"throughput (intended outlets)\",t/h,1,1,4,110,12,4,0,\"\"\n"
                                                                          "\"outlet bin\",t/h,1,1,4,50.5,4,1,0,\"\"\n"
                                                                          "\"outlet spill\",t/h,1,1,4,5,1,1,0,\"\"\n"
                                                                          "\"kinetic energy\",J,1,1,4,21,2,0.5,0,\"\"\n");
  write(dir / "report" / "drives.csv", std::string(kDrivesHeader) + "\"belt\",belt,pull,N,150,10,40,120,1,4\n"
                                                                     "\"belt\",belt,power,W,600,30,90,120,1,4\n");
  write(dir / "report" / "mesh_loads.csv", std::string(kLoadsHeader) + "chute,fz,N,-1000,20,80,120,1,4\n");
  write(dir / "report" / "metrics.csv", "name,value\nsteady,1\n# steady_text: steady from 1 s to 4 s (throughput (intended outlets))\n"
                                        "throughput_t_h,110\npower_total_W,450\ndrive_screw_torque_N_m,12\nliner_life_min_months,24\n");
}

/// Two synthetic runs in a fresh folder under the temporary directory.
struct TwoRuns {
  fs::path dir, a, b;
  explicit TwoRuns(const std::string& name) : dir(fs::temp_directory_path() / name), a(dir / "chute"), b(dir / "chute_v2") {
    fs::remove_all(dir);
    write_run_a(a);
    write_run_b(b);
  }
  ~TwoRuns() { fs::remove_all(dir); }
  report::RunComparison compare() const { return report::compare_runs(report::read_run_tables(a.string()), report::read_run_tables(b.string())); }
};

const report::FigureComparison& figure(const report::RunComparison& c, const std::string& name) {
  for (const report::FigureComparison& f : c.figures)
    if (f.name == name) return f;
  throw std::runtime_error("no figure " + name);
}

bool lists(const std::vector<report::RunFigure>& figures, const std::string& name) {
  for (const report::RunFigure& f : figures)
    if (f.name == name) return true;
  return false;
}

TEST(CompareRuns, DifferenceItsStandardErrorAndZExactly) {
  const TwoRuns runs("demdesign_compare_runs_z_test");
  const report::RunComparison c = runs.compare();
  // A 100 +- 3, B 110 +- 4: B - A = 10 +- sqrt(9 + 16) = 5, z = 2: at the threshold, B higher.
  const report::FigureComparison& throughput = figure(c, "throughput (intended outlets)");
  EXPECT_DOUBLE_EQ(throughput.a, 100);
  EXPECT_DOUBLE_EQ(throughput.a_std_error, 3);
  EXPECT_DOUBLE_EQ(throughput.b, 110);
  EXPECT_DOUBLE_EQ(throughput.b_std_error, 4);
  EXPECT_DOUBLE_EQ(throughput.difference, 10);
  EXPECT_DOUBLE_EQ(throughput.difference_std_error, 5);
  EXPECT_DOUBLE_EQ(throughput.z, 2.0);
  EXPECT_DOUBLE_EQ(throughput.change_pct, 10);
  EXPECT_EQ(throughput.verdict, "B higher");
  EXPECT_EQ(throughput.unit, "t/h");
  EXPECT_EQ(throughput.group, report::FigureGroup::throughput);
  // 50 +- 1 against 50.5 +- 1: z = 0.5 / sqrt(2).
  const report::FigureComparison& outlet = figure(c, "outlet bin");
  EXPECT_DOUBLE_EQ(outlet.difference_std_error, std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(outlet.z, 0.5 / std::sqrt(2.0));
  EXPECT_EQ(outlet.verdict, "no difference the runs can show");
  // The belt from drives.csv (steady_state.csv's 999 is left out): 200 +- 10 against 150 +- 10.
  const report::FigureComparison& pull = figure(c, "drive pull belt");
  EXPECT_EQ(pull.source, "drives.csv");
  EXPECT_EQ(pull.group, report::FigureGroup::drives);
  EXPECT_EQ(pull.unit, "N");
  EXPECT_DOUBLE_EQ(pull.a, 200);
  EXPECT_DOUBLE_EQ(pull.z, -50 / std::sqrt(200.0));
  EXPECT_EQ(pull.verdict, "B lower");
  const report::FigureComparison& load = figure(c, "force z on chute");
  EXPECT_EQ(load.source, "mesh_loads.csv");
  EXPECT_EQ(load.group, report::FigureGroup::loads);
  EXPECT_DOUBLE_EQ(load.z, 0);
  // A series that found no steady state in A says so.
  EXPECT_EQ(figure(c, "kinetic energy").note, "A not steady");
}

TEST(CompareRuns, MetricsCarryAMeanOnlyWithTheirUnits) {
  const TwoRuns runs("demdesign_compare_runs_metrics_test");
  const report::RunComparison c = runs.compare();
  const report::FigureComparison& power = figure(c, "power_total_W");
  EXPECT_EQ(power.unit, "W");
  EXPECT_EQ(power.group, report::FigureGroup::drives);
  EXPECT_DOUBLE_EQ(power.difference, -150);
  EXPECT_TRUE(std::isnan(power.difference_std_error));
  EXPECT_TRUE(std::isnan(power.z));
  EXPECT_NE(power.verdict.find("mean only"), std::string::npos) << power.verdict;
  EXPECT_EQ(figure(c, "drive_screw_torque_N_m").unit, "N m");
  EXPECT_EQ(figure(c, "throughput_t_h").unit, "t/h");
  const report::FigureComparison& life = figure(c, "liner_life_min_months");
  EXPECT_EQ(life.unit, "months");
  EXPECT_EQ(life.group, report::FigureGroup::wear);
  EXPECT_DOUBLE_EQ(life.difference, 6);
}

TEST(CompareRuns, FiguresOfOneRunOnlyAreListed) {
  const TwoRuns runs("demdesign_compare_runs_only_test");
  const report::RunComparison c = runs.compare();
  EXPECT_TRUE(lists(c.only_b, "outlet spill"));
  EXPECT_TRUE(lists(c.only_a, "contacts"));
  EXPECT_FALSE(lists(c.only_a, "outlet spill"));
  for (const report::FigureComparison& f : c.figures) EXPECT_NE(f.name, "outlet spill");
}

TEST(CompareRuns, NamesTheKeysInWhichTheCasesDiffer) {
  const TwoRuns runs("demdesign_compare_runs_keys_test");
  const report::RunComparison c = runs.compare();
  const auto has = [&c](const std::string& key) { return std::find(c.differing_keys.begin(), c.differing_keys.end(), key) != c.differing_keys.end(); };
  EXPECT_TRUE(has("equipment.transfer_chute.spoon.radius"));
  EXPECT_TRUE(has("wear (only in B)"));
  EXPECT_FALSE(has("simulation.duration")) << "4 and 4.0 are one value";
  EXPECT_EQ(c.differing_keys.size(), 2u);
  bool hash_named = false;
  for (const std::string& note : c.input_notes) hash_named |= note.find("model_hash 00000000000000aa in A, 00000000000000bb in B") != std::string::npos;
  EXPECT_TRUE(hash_named);
  EXPECT_EQ(c.b.inputs.case_header, "v01 of cases/chute.yaml: spoon.radius=1.0");
  EXPECT_EQ(c.a.inputs.end_text, "t = 4 s, completed");
}

TEST(CompareRuns, AReportFolderGivenItselfIsReadAsItsRun) {
  const TwoRuns runs("demdesign_compare_runs_report_folder_test");
  const report::RunTables from_run = report::read_run_tables(runs.a.string());
  const report::RunTables from_report = report::read_run_tables((runs.a / "report").string());
  EXPECT_EQ(from_report.figures.size(), from_run.figures.size());
  EXPECT_EQ(from_report.inputs.model_hash, "00000000000000aa");
}

TEST(CompareRuns, WritesCsvAndHtml) {
  const TwoRuns runs("demdesign_compare_runs_files_test");
  const fs::path out = runs.dir / "compared";
  report::write_compare_report(runs.compare(), out.string());
  const std::string csv = read(out / "compare.csv");
  EXPECT_EQ(csv.rfind("group,figure,unit,source,a_mean,a_std_error,b_mean,b_std_error,difference,difference_std_error,z,change_pct,verdict,note\n", 0), 0u);
  EXPECT_NE(csv.find("\nthroughput,throughput (intended outlets),t/h,steady_state.csv,100,3,110,4,10,5,2,10,B higher,\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nthroughput,outlet spill,t/h,steady_state.csv,,,5,1,,,,,only in B,\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nother,contacts,-,steady_state.csv,3000,20,,,,,,,only in A,\n"), std::string::npos) << csv;
  const std::string html = read(out / "compare.html");
  for (const char* text : {"Two runs compared", "Throughput and outlets", "Drives", "Loads on the meshes", "Wear and liner life", "B higher",
                           "B lower", "no difference the runs can show", "Only in B", "equipment.transfer_chute.spoon.radius", "compare.csv"})
    EXPECT_NE(html.find(text), std::string::npos) << text;
  // The bar plot of z: its data (the throughput first, a bar from 0 to 2, beyond two standard
  // errors) and script are written; the PNG where gnuplot is installed, a note where it is not.
  EXPECT_NE(read(out / "compare_z.tsv").find("\n1\t0\t2\t1\n"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "compare_z.gp"));
  EXPECT_TRUE(html.find("data:image/png;base64,") != std::string::npos || html.find("Plot not drawn") != std::string::npos);
}

TEST(CompareRuns, ExactFiguresDifferWithCertainty) {
  report::RunFigure a{"particles", "-", "steady_state.csv", report::FigureGroup::other, 5, 0, true};
  report::RunFigure b = a;
  EXPECT_DOUBLE_EQ(report::compare_figure(a, b).z, 0);
  EXPECT_EQ(report::compare_figure(a, b).verdict, "no difference the runs can show");
  b.mean = 6;
  EXPECT_TRUE(std::isinf(report::compare_figure(a, b).z));
  EXPECT_EQ(report::compare_figure(a, b).verdict, "B higher");
}

TEST(CompareRuns, AMissingFolderOrTableIsNamed) {
  const TwoRuns runs("demdesign_compare_runs_missing_test");
  const fs::path nowhere = runs.dir / "never_run";
  try {
    report::read_run_tables(nowhere.string());
    ADD_FAILURE() << "a missing folder was read";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find(nowhere.string() + ": no such folder"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Run the case first"), std::string::npos) << e.what();
  }
  fs::remove(runs.b / "report" / "steady_state.csv");
  try {
    report::read_run_tables(runs.b.string());
    ADD_FAILURE() << "a run without steady_state.csv was read";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find((runs.b / "report" / "steady_state.csv").string() + ": missing"), std::string::npos) << e.what();
  }
  // A run without its report (--no-report) is told apart from a folder no run wrote.
  fs::remove_all(runs.a / "report");
  try {
    report::read_run_tables(runs.a.string());
    ADD_FAILURE() << "a run without its report was read";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("holds a run without its report"), std::string::npos) << e.what();
  }
}

TEST(CompareRuns, DefaultFolderLiesBesideA) {
  EXPECT_EQ(report::default_compare_folder("out/chute", "out/chute_v2"), "out/compare_chute_chute_v2");
  EXPECT_EQ(report::default_compare_folder("out/chute/", "elsewhere/b"), "out/compare_chute_b");
  EXPECT_EQ(report::default_compare_folder("chute", "b"), "compare_chute_b");
}

}  // namespace
}  // namespace dem::test
