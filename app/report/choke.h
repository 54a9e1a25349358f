// The chute's narrowest section against the stream that passes it (the choke margin), and the
// stream's profiles across the chute and on the receiving belt (internal to app/).
// report_analysis.cpp finds them (find_choke_and_profiles), adds the metrics choke_fill and
// choke_margin and writes choke.csv; report.cpp draws the section "Choke and stream profile".
//
// Fill: the time-mean mass m in the box across the section (sensor stream_chute, over the run's
// interval, mean and standard error by batch means), over the mass the section would hold at the
// material's poured bulk density rho: fill = m / (rho A L), A the section's free area
// (choke_section_area_m2) and L the box's length along the flow (choke_section_length_m), both
// design values of the generator (equipment/transfer_chute_sensors.cpp). Margin = 1 - fill. The profiles
// come from the run's stream profile sensors (statistics/stream_profile.h), the same numbers as
// its stream_profiles.csv; a bin's depth is its mean mass over rho, its width and the length.
#pragma once

#include <string>
#include <vector>

#include "report/belt_capacity.h"
#include "report/report.h"
#include "report/report_internal.h"

namespace dem::report {

struct RunAnalysis;

/// The box sensor across a chute's narrowest section.
inline constexpr const char* kChokeSensor = "stream_chute";

/// Fills below which a section runs ample, and adequate. That a chute should run at most one
/// third full at its narrowest section is a common design rule; no published source is checked
/// here, so the report states it as assumed. Two thirds is this report's own line between a
/// section that still has room for surges and one that chokes.
inline constexpr double kAmpleFill = 1.0 / 3.0;
inline constexpr double kAdequateFill = 2.0 / 3.0;
/// The rule as the report and choke.csv state it.
extern const char* const kChokeRule;

/// How full a section runs against the rule.
enum class ChokeVerdict {
  ample,     ///< fill < 1/3: the design rule met
  adequate,  ///< 1/3 to 2/3: room for surges, less than the rule asks
  tight,     ///< 2/3 to 1: a surge or build-up can choke it
  choked,    ///< >= 1: the stream fills the section at its poured bulk density
  unknown,   ///< no fill (NaN)
};
ChokeVerdict choke_verdict(double fill);
/// "ample", "adequate", "tight: choke risk", "choked", "unknown".
const char* choke_verdict_text(ChokeVerdict verdict);

/// How full a section runs.
struct ChokeFill {
  double fill = kNaN;        ///< [-] m / (rho A L)
  double fill_error = kNaN;  ///< [-] its standard error, from the mass's
  double margin = kNaN;      ///< [-] 1 - fill (its error is the fill's)
  ChokeVerdict verdict = ChokeVerdict::unknown;
};
/// The fill of a section of free area `area` [m^2] over `length` [m] along the flow holding a
/// mean mass `mass` [kg] (standard error `mass_error` [kg]) of a material of poured bulk density
/// `bulk_density` [kg/m^3]. Non-positive or NaN bulk density, area or length give NaN.
ChokeFill choke_fill(double mass, double mass_error, double bulk_density, double area, double length);

/// The run's narrowest section and its fill; `sensor` empty when the run has no choke sensor.
struct ChokeResult {
  std::string sensor;
  std::string missing;  ///< why there is no fill ("" when there is one)
  double area = kNaN;    ///< [m^2] choke_section_area_m2
  double length = kNaN;  ///< [m] choke_section_length_m
  double height = kNaN;  ///< [m] choke_section_at_height_m (NaN when not given)
  /// [kg] Mean mass in the box over the run's interval and its standard error, of the real
  /// material (divided by the mass scaling).
  double mass = kNaN, mass_error = kNaN;
  MaterialFacts material;
  ChokeFill fill;
};

/// One binned sensor's stream profile over the records window, with its depths.
struct StreamProfile {
  std::string sensor;
  std::vector<double> lateral;   ///< [m] bin centres along `across` from the box centre
  std::vector<double> mass;      ///< [kg] time-mean mass per bin (real material)
  std::vector<double> depth;     ///< [m] per bin (stream_depth)
  std::vector<double> velocity;  ///< [m/s] per bin along the sensor's `along`, mass weighted
  double width = 0;   ///< [m] of a bin
  double length = 0;  ///< [m] the box's length along `along`
  double window = 0;  ///< [s] the records window the means are over
};

/// [m] The depth of a bin: its mean mass [kg] spread at bulk density [kg/m^3] over its width [m]
/// and the box's length along the flow [m]; NaN unless all three are positive.
double stream_depth(double mass, double bulk_density, double width, double length);

/// The choke (run.choke) and the stream profiles (run.profiles). Needs run.boxes finished.
void find_choke_and_profiles(const RunReportInput& in, RunAnalysis& run);
/// Appends choke_fill and choke_margin when the run has a fill.
void add_choke_metrics(RunAnalysis& run);
/// choke.csv into report_dir when the run has a fill; nothing otherwise.
void write_choke_csv(const RunAnalysis& run, const std::string& report_dir);

}  // namespace dem::report
