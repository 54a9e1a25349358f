#include "statistics/events.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace dem {

namespace {

constexpr double kNever = std::numeric_limits<double>::infinity();

/// When a centre now inside [lo, hi] on every axis entered the box, moving at v: the latest of
/// the axes' entry times (each the time it crossed the face it came through), at most `now`.
double entry_time(const double x[3], const double v[3], const double lo[3], const double hi[3], double now) {
  double entered = -kNever;
  for (int a = 0; a < 3; ++a) {
    if (v[a] > 0) entered = std::max(entered, now - (x[a] - lo[a]) / v[a]);
    else if (v[a] < 0) entered = std::max(entered, now - (hi[a] - x[a]) / -v[a]);
  }
  return entered;
}

/// When a centre now outside [lo, hi] left it: the earliest crossing of a face it is beyond.
double exit_time(const double x[3], const double v[3], const double lo[3], const double hi[3], double now) {
  double left = now;
  for (int a = 0; a < 3; ++a) {
    if (x[a] > hi[a] && v[a] > 0) left = std::min(left, now - (x[a] - hi[a]) / v[a]);
    else if (x[a] < lo[a] && v[a] < 0) left = std::min(left, now - (lo[a] - x[a]) / -v[a]);
  }
  return left;
}

}  // namespace

EventWatch::EventWatch(const Model& model) {
  for (std::size_t k = 0; k < model.outlets.size(); ++k)
    watches_.push_back({Watch::Kind::outlet, k, "first at outlet " + model.outlets[k].name});
  for (std::size_t k = 0; k < model.sensors.size(); ++k)
    if (model.sensors[k].kind == SensorSpec::Kind::plane) watches_.push_back({Watch::Kind::sensor, k, "first across sensor " + model.sensors[k].name});
  if (model.has_domain && model.domain_outlet < 0) watches_.push_back({Watch::Kind::domain, 0, "first out of the domain"});
}

void EventWatch::restore(const std::vector<RunEvent>& earlier) {
  for (const RunEvent& e : earlier)
    for (Watch& w : watches_)
      if (!w.done && w.what == e.what) w.done = true, fired_.push_back(e);
}

bool EventWatch::pending() const {
  return std::any_of(watches_.begin(), watches_.end(), [](const Watch& w) { return !w.done; });
}

bool EventWatch::check(const Model& model, const State& s, double since) {
  if (!pending()) return false;
  const double now = s.time, dt = model.dt;
  const double domain_lo[3] = {model.domain_min[0], model.domain_min[1], model.domain_min[2]};
  const double domain_hi[3] = {model.domain_max[0], model.domain_max[1], model.domain_max[2]};
  // When a centre outside the domain (along a non-periodic axis) left it; never when inside.
  const auto left_domain = [&](const double x[3], const double v[3]) {
    bool out = false;
    for (int a = 0; a < 3; ++a) out |= model.period[a] <= 0 && (x[a] < domain_lo[a] || x[a] > domain_hi[a]);
    return out ? exit_time(x, v, domain_lo, domain_hi, now) : kNever;
  };
  bool any = false;
  for (Watch& w : watches_) {
    if (w.done) continue;
    double best = kNever;
    std::int64_t who = -1;
    for (std::size_t p = 0; p < s.owned(); ++p) {
      const double x[3] = {s.x[p], s.y[p], s.z[p]}, v[3] = {s.vx[p], s.vy[p], s.vz[p]};
      double at = kNever;
      if (w.kind == Watch::Kind::outlet) {
        const OutletSpec& o = model.outlets[w.index];
        if (o.domain) {
          at = left_domain(x, v);
        } else {
          const double lo[3] = {o.region_min.x(), o.region_min.y(), o.region_min.z()}, hi[3] = {o.region_max.x(), o.region_max.y(), o.region_max.z()};
          if (x[0] >= lo[0] && x[0] <= hi[0] && x[1] >= lo[1] && x[1] <= hi[1] && x[2] >= lo[2] && x[2] <= hi[2]) at = entry_time(x, v, lo, hi, now);
        }
      } else if (w.kind == Watch::Kind::sensor) {
        const SensorSpec& sensor = model.sensors[w.index];
        const Vec3& n = sensor.normal;
        if (x[0] < sensor.region_min.x() || x[0] > sensor.region_max.x() || x[1] < sensor.region_min.y() || x[1] > sensor.region_max.y() ||
            x[2] < sensor.region_min.z() || x[2] > sensor.region_max.z())
          continue;
        const double past = (x[0] - sensor.point.x()) * n.x() + (x[1] - sensor.point.y()) * n.y() + (x[2] - sensor.point.z()) * n.z();
        const double along = v[0] * n.x() + v[1] * n.y() + v[2] * n.z();
        if (past >= 0 && past <= 0.5 * sensor.thickness && along > 0) at = now - past / along;
      } else {
        at = left_domain(x, v);
      }
      if (at < best) best = at, who = s.id[p];
    }
    // The particle may already be gone, removed at a list rebuild since the last check: traced
    // back from where and when it was removed.
    const State::Removal* removal = w.kind == Watch::Kind::domain ? &s.first_lost
                                    : w.kind == Watch::Kind::outlet && w.index < s.first_removed.size() ? &s.first_removed[w.index]
                                                                                                         : nullptr;
    if (removal && removal->time >= 0) {
      const State::LostParticle& q = removal->particle;
      const double x[3] = {q.x, q.y, q.z}, v[3] = {q.vx, q.vy, q.vz};
      const OutletSpec* o = w.kind == Watch::Kind::outlet ? &model.outlets[w.index] : nullptr;
      double at = removal->time;
      if (!o || o->domain) {
        at = exit_time(x, v, domain_lo, domain_hi, removal->time);
      } else {
        const double lo[3] = {o->region_min.x(), o->region_min.y(), o->region_min.z()}, hi[3] = {o->region_max.x(), o->region_max.y(), o->region_max.z()};
        at = entry_time(x, v, lo, hi, removal->time);
      }
      if (at < best) best = at, who = q.id;
    }
    if (best == kNever) continue;
    // To the step: the first step at or after the crossing, not before the previous check.
    const double at = std::clamp(best, since, now);
    const auto steps_back = static_cast<std::int64_t>(std::floor((now - at) / dt + 1e-9));
    fired_.push_back({w.what, now - static_cast<double>(steps_back) * dt, s.step - steps_back, who});
    w.done = true, any = true;
  }
  return any;
}

std::string events_csv(const std::vector<RunEvent>& events) {
  std::vector<RunEvent> sorted = events;
  std::stable_sort(sorted.begin(), sorted.end(), [](const RunEvent& a, const RunEvent& b) { return a.step < b.step; });
  std::string out = "what,time_s,step,particle_id\n";
  for (const RunEvent& e : sorted) out += fmt::format("{},{:.9g},{},{}\n", e.what, e.time, e.step, e.particle);
  return out;
}

std::vector<RunEvent> read_events(const std::string& path, double time) {
  std::vector<RunEvent> out;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    RunEvent e;
    std::string cell;
    if (!std::getline(fields, e.what, ',') || !std::getline(fields, cell, ',')) continue;
    e.time = std::stod(cell);
    if (!std::getline(fields, cell, ',')) continue;
    e.step = std::stoll(cell);
    if (std::getline(fields, cell, ',')) e.particle = std::stoll(cell);
    if (e.time <= time + 1e-12) out.push_back(e);
  }
  return out;
}

}  // namespace dem
