// Stream profiles: what a stream looks like across a box sensor with bins (SensorSpec::bins), the
// mass and the velocity along the flow in equal lateral bins, averaged over the run's records
// window (output.records_from on). At each row of scalars the sensors' sums (diagnostics.cpp)
// hold each bin's mass and momentum along the flow, summed over the ranks with the rest of the
// row; accumulate_stream_profiles integrates them over time into State::stream_profiles, which a
// checkpoint keeps; the run writes their means to stream_profiles.csv at its end, and the report
// turns them into depths with the material's bulk density (app/report/choke.h).
//
// Rejected: integrating at every step (the sums run only at the rows, as the other sensor sums
// do, so the per-particle cost stays that of one row), and a time series of every bin in
// scalars.csv (a profile is a mean; its bins are many columns that nothing reads row by row).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "base/vec3.h"
#include "case/spec.h"
#include "core/model.h"
#include "core/state.h"
#include "statistics/diagnostics.h"

namespace dem {

/// Whether a sensor measures a stream profile: a box with bins.
inline bool has_profile(const SensorSpec& sensor) { return sensor.kind == SensorSpec::Kind::box && sensor.bins > 0; }

/// [m] The extent of the box [lo, hi] along the unit direction u: sum |u_i| (hi_i - lo_i).
double box_extent(const Vec3& lo, const Vec3& hi, const Vec3& u);

/// The lateral bins of a box sensor: `count` equal bins across the box's extent along `across`,
/// positions measured along `across` from the box centre; and the box's length along `along`.
struct ProfileBins {
  int count = 0;
  double lateral_min = 0;  // [m] the outer edge of bin 0
  double width = 0;        // [m] of each bin
  double length = 0;       // [m] the box's extent along `along`
  /// The bin holding lateral position `lateral` [m]; the box's edges belong to the end bins.
  int bin(double lateral) const;
  /// [m] The centre of bin k.
  double centre(int k) const { return lateral_min + (k + 0.5) * width; }
};
/// The bins of `sensor` (count 0 without a profile); `across` and `along` unit vectors (compile).
ProfileBins profile_bins(const SensorSpec& sensor);

/// Bins of all the model's binned sensors together: the length of StreamProfiles' columns.
std::size_t profile_bin_total(const Model& model);

/// Adds a row's binned readings (SensorReading::bin_mass, bin_momentum) to state.stream_profiles,
/// each held for the time since the row before that lies after output.records_from (the row's
/// reading stands for its interval, the rule of the rows' mesh loads). The first row only starts
/// the clock; profiles of another size (a checkpoint of other sensors) start again. Every rank
/// calls it with the same row.
void accumulate_stream_profiles(const Model& model, const Scalars& row, State& state);

/// One bin of a stream profile over the records window: a row of stream_profiles.csv.
struct StreamProfileRow {
  std::string sensor;
  int bin = 0;
  double lateral = 0;   // [m] bin centre along `across` from the box centre
  double width = 0;     // [m] the bin's width along `across`
  double length = 0;    // [m] the box's length along `along`
  double mass = 0;      // [kg] time-mean mass in the bin
  double velocity = 0;  // [m/s] mean velocity along `along`, weighted by mass and time (0 without mass)
  double window = 0;    // [s] the time the means are over
};
/// The rows of every binned sensor of `model` from `profiles`; none when their size does not
/// match the model's bins.
std::vector<StreamProfileRow> stream_profile_rows(const Model& model, const StreamProfiles& profiles);
/// stream_profiles.csv: sensor,bin,lateral_m,bin_width_m,length_along_m,mean_mass_kg,
/// mean_velocity_m_s,window_s, one line a row.
std::string stream_profiles_csv(const std::vector<StreamProfileRow>& rows);

}  // namespace dem
