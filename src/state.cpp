#include "state.h"

#include <cstddef>
#include <numbers>

using std::size_t;

namespace dem {

namespace {
template <typename T>
void apply_order(std::vector<T>& column, const std::vector<std::int32_t>& order, std::vector<T>& scratch) {
  scratch.resize(order.size());
  for (size_t k = 0; k < order.size(); ++k) scratch[k] = column[order[k]];
  column.swap(scratch);
}
template <typename T>
void keep_only(std::vector<T>& column, const std::vector<std::uint8_t>& keep) {
  size_t out = 0;
  for (size_t k = 0; k < column.size(); ++k)
    if (keep[k]) column[out++] = column[k];
  column.resize(out);
}
}  // namespace

std::size_t State::add_sphere(double px, double py, double pz, double r, double density, int mat) {
  const double mass = density * 4.0 / 3.0 * std::numbers::pi * r * r * r;
  x.push_back(px), y.push_back(py), z.push_back(pz);
  for (auto* c : {&vx, &vy, &vz, &wx, &wy, &wz, &fx, &fy, &fz, &tx, &ty, &tz}) c->push_back(0.0);
  radius.push_back(r);
  inv_mass.push_back(1.0 / mass);
  inv_inertia.push_back(1.0 / (0.4 * mass * r * r));
  material.push_back(mat);
  id.push_back(next_id++);
  return x.size() - 1;
}

void State::permute(const std::vector<std::int32_t>& order) {
  std::vector<double> scratch;
  for (auto* c : {&x, &y, &z, &vx, &vy, &vz, &wx, &wy, &wz, &fx, &fy, &fz, &tx, &ty, &tz, &radius, &inv_mass, &inv_inertia})
    apply_order(*c, order, scratch);
  std::vector<std::int32_t> s32;
  apply_order(material, order, s32);
  std::vector<std::int64_t> s64;
  apply_order(id, order, s64);
}

void State::compact(const std::vector<std::uint8_t>& keep) {
  for (auto* c : {&x, &y, &z, &vx, &vy, &vz, &wx, &wy, &wz, &fx, &fy, &fz, &tx, &ty, &tz, &radius, &inv_mass, &inv_inertia})
    keep_only(*c, keep);
  keep_only(material, keep);
  keep_only(id, keep);
}

}  // namespace dem
