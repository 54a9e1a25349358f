#include "diagnostics.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace dem {

namespace {

double pair_overlap(const State& s, size_t i, size_t j) {
  const double dx = s.x[i] - s.x[j], dy = s.y[i] - s.y[j], dz = s.z[i] - s.z[j];
  return s.radius[i] + s.radius[j] - std::sqrt(dx * dx + dy * dy + dz * dz);
}

double wall_overlap(const Model& m, const State& s, size_t i, size_t w) {
  const PlaneWall& wall = m.planes[w];
  return s.radius[i] - ((s.x[i] - wall.point[0]) * wall.normal[0] + (s.y[i] - wall.point[1]) * wall.normal[1] +
                        (s.z[i] - wall.point[2]) * wall.normal[2]);
}

std::uint64_t mix(std::uint64_t h, double v) {
  const auto* p = reinterpret_cast<const unsigned char*>(&v);
  for (size_t k = 0; k < sizeof v; ++k) h = (h ^ p[k]) * 0x100000001b3ULL;
  return h;
}

}  // namespace

Scalars measure(const Model& model, const State& s, const Workspace& work) {
  Scalars out;
  out.time = s.time;
  out.step = s.step;
  out.particles = s.size();
  out.dt = model.dt;
  out.lost = s.lost;
  for (size_t p = 0; p < s.size(); ++p) {
    const double m = 1.0 / s.inv_mass[p], inertia = 1.0 / s.inv_inertia[p];
    out.kinetic_translation += 0.5 * m * (s.vx[p] * s.vx[p] + s.vy[p] * s.vy[p] + s.vz[p] * s.vz[p]);
    out.kinetic_rotation += 0.5 * inertia * (s.wx[p] * s.wx[p] + s.wy[p] * s.wy[p] + s.wz[p] * s.wz[p]);
  }
  double sum = 0;
  auto count = [&](double overlap, double radius) {
    if (overlap <= 0) return;
    ++out.contacts;
    sum += overlap / radius;
    out.max_overlap_ratio = std::max(out.max_overlap_ratio, overlap / radius);
  };
  for (size_t k = 0; k < s.pairs.size(); ++k)
    count(pair_overlap(s, s.pairs.i[k], s.pairs.j[k]), std::min(s.radius[s.pairs.i[k]], s.radius[s.pairs.j[k]]));
  for (size_t k = 0; k < s.wall_pairs.size(); ++k)
    count(wall_overlap(model, s, s.wall_pairs.i[k], s.wall_pairs.j[k]), s.radius[s.wall_pairs.i[k]]);
  out.mean_overlap_ratio = out.contacts ? sum / static_cast<double>(out.contacts) : 0.0;
  return out;
}

std::uint64_t state_hash(const State& s, int width) {
  std::vector<size_t> by_id(s.size());
  std::iota(by_id.begin(), by_id.end(), 0);
  std::sort(by_id.begin(), by_id.end(), [&](size_t a, size_t b) { return s.id[a] < s.id[b]; });
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (size_t p : by_id)
    for (double v : {s.x[p], s.y[p], s.z[p], s.vx[p], s.vy[p], s.vz[p], s.wx[p], s.wy[p], s.wz[p]}) h = mix(h, v);
  // Contact histories keyed by (id, id) in sorted order.
  std::vector<std::tuple<std::int64_t, std::int64_t, size_t>> keys;
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    const auto a = s.id[s.pairs.i[k]], b = s.id[s.pairs.j[k]];
    keys.emplace_back(std::min(a, b), std::max(a, b), k);
  }
  std::sort(keys.begin(), keys.end());
  for (const auto& [a, b, k] : keys)
    for (int q = 0; q < width; ++q) h = mix(h, s.pairs.history[k * width + q]);
  return h;
}

void check_numerics(const Model& model, const State& s, const Workspace& work, double max_overlap_ratio) {
  for (size_t p = 0; p < s.size(); ++p) {
    const double values[] = {s.x[p], s.y[p], s.z[p], s.vx[p], s.vy[p], s.vz[p], s.wx[p], s.wy[p], s.wz[p]};
    for (double v : values) {
      if (std::isfinite(v)) continue;
      throw NumericalError(fmt::format(
          "t = {:.6g} s, step {}: particle {} has a non-finite position or velocity (x = [{:g}, {:g}, {:g}]).\n"
          "Likely cause: the time step {:.3g} s is too large for the contact stiffness ({}); use time_step: auto.",
          s.time, s.step, s.id[p], s.x[p], s.y[p], s.z[p], model.dt, model.advice.report));
    }
  }
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    const size_t i = s.pairs.i[k], j = s.pairs.j[k];
    const double ratio = pair_overlap(s, i, j) / std::min(s.radius[i], s.radius[j]);
    if (ratio > max_overlap_ratio)
      throw NumericalError(fmt::format(
          "t = {:.6g} s, step {}: particles {} and {} overlap by {:.0f} % of the smaller radius at [{:.4g}, {:.4g}, {:.4g}] m "
          "(limit {:.0f} %).\nLikely causes: a time step too large for the stiffness ({}), or particles inserted into "
          "each other.",
          s.time, s.step, s.id[i], s.id[j], 100 * ratio, s.x[i], s.y[i], s.z[i], 100 * max_overlap_ratio, model.advice.report));
  }
  for (size_t k = 0; k < s.wall_pairs.size(); ++k) {
    const size_t i = s.wall_pairs.i[k];
    const double ratio = wall_overlap(model, s, i, s.wall_pairs.j[k]) / s.radius[i];
    if (ratio > max_overlap_ratio)
      throw NumericalError(fmt::format(
          "t = {:.6g} s, step {}: particle {} overlaps wall '{}' by {:.0f} % of its radius at [{:.4g}, {:.4g}, {:.4g}] m "
          "(limit {:.0f} %).\nLikely causes: a wall stiffness too low for the load, or a time step too large ({}).",
          s.time, s.step, s.id[i], model.planes[s.wall_pairs.j[k]].name, 100 * ratio, s.x[i], s.y[i], s.z[i],
          100 * max_overlap_ratio, model.advice.report));
  }
}

}  // namespace dem
