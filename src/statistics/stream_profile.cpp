#include "statistics/stream_profile.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace dem {

double box_extent(const Vec3& lo, const Vec3& hi, const Vec3& u) {
  return std::abs(u.x()) * (hi.x() - lo.x()) + std::abs(u.y()) * (hi.y() - lo.y()) + std::abs(u.z()) * (hi.z() - lo.z());
}

int ProfileBins::bin(double lateral) const {
  // Clamped as a double first: a position just outside by rounding (or not a number) stays in range.
  const double k = std::floor((lateral - lateral_min) / width);
  if (!(k >= 0)) return 0;
  if (k >= count - 1) return count - 1;
  return static_cast<int>(k);
}

ProfileBins profile_bins(const SensorSpec& sensor) {
  ProfileBins b;
  if (!has_profile(sensor)) return b;
  const double extent = box_extent(sensor.region_min, sensor.region_max, sensor.across.normalized());  // [m]
  b.count = sensor.bins;
  b.lateral_min = -0.5 * extent;
  b.width = extent / sensor.bins;
  b.length = box_extent(sensor.region_min, sensor.region_max, sensor.along.normalized());
  return b;
}

std::size_t profile_bin_total(const Model& model) {
  std::size_t total = 0;
  for (const SensorSpec& sensor : model.sensors)
    if (has_profile(sensor)) total += static_cast<std::size_t>(sensor.bins);
  return total;
}

void accumulate_stream_profiles(const Model& model, const Scalars& row, State& state) {
  const std::size_t total = profile_bin_total(model);
  if (total == 0) return;
  StreamProfiles& p = state.stream_profiles;
  if (p.mass_time.size() != total || p.momentum_time.size() != total) {
    p = StreamProfiles{};
    p.mass_time.assign(total, 0.0), p.momentum_time.assign(total, 0.0);
  }
  // The reading holds for the part of the interval since the row before that lies in the window.
  const double held = p.has_row ? row.time - std::max(p.last_row_time, model.output.records_from) : 0.0;  // [s]
  p.has_row = true, p.last_row_time = row.time;
  if (!(held > 0)) return;
  std::size_t first = 0;
  for (std::size_t k = 0; k < model.sensors.size(); ++k) {
    if (!has_profile(model.sensors[k])) continue;
    const std::size_t n = static_cast<std::size_t>(model.sensors[k].bins);
    const bool read = k < row.sensors.size() && row.sensors[k].bin_mass.size() == n && row.sensors[k].bin_momentum.size() == n;
    for (std::size_t j = 0; j < n && read; ++j) {
      p.mass_time[first + j] += row.sensors[k].bin_mass[j] * held;
      p.momentum_time[first + j] += row.sensors[k].bin_momentum[j] * held;
    }
    first += n;
  }
  p.window += held;
}

std::vector<StreamProfileRow> stream_profile_rows(const Model& model, const StreamProfiles& profiles) {
  std::vector<StreamProfileRow> rows;
  const std::size_t total = profile_bin_total(model);
  if (total == 0 || profiles.mass_time.size() != total || profiles.momentum_time.size() != total) return rows;
  std::size_t first = 0;
  for (const SensorSpec& sensor : model.sensors) {
    if (!has_profile(sensor)) continue;
    const ProfileBins bins = profile_bins(sensor);
    for (int k = 0; k < bins.count; ++k) {
      const std::size_t at = first + static_cast<std::size_t>(k);
      const double mass_time = profiles.mass_time[at], momentum_time = profiles.momentum_time[at];  // [kg s], [kg m]
      StreamProfileRow r;
      r.sensor = sensor.name, r.bin = k;
      r.lateral = bins.centre(k), r.width = bins.width, r.length = bins.length;
      r.mass = profiles.window > 0 ? mass_time / profiles.window : 0.0;
      r.velocity = mass_time > 0 ? momentum_time / mass_time : 0.0;
      r.window = profiles.window;
      rows.push_back(std::move(r));
    }
    first += static_cast<std::size_t>(bins.count);
  }
  return rows;
}

std::string stream_profiles_csv(const std::vector<StreamProfileRow>& rows) {
  std::string out = "sensor,bin,lateral_m,bin_width_m,length_along_m,mean_mass_kg,mean_velocity_m_s,window_s\n";
  for (const StreamProfileRow& r : rows)
    out += fmt::format("{},{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n", r.sensor, r.bin, r.lateral, r.width, r.length, r.mass,
                       r.velocity, r.window);
  return out;
}

}  // namespace dem
