#include "core/state.h"

#include "base/allocator.h"
#include "base/parallel.h"

#include <algorithm>
#include <array>
#include <initializer_list>
#include <cstddef>
#include <numbers>

using std::size_t;

namespace dem {

namespace {
/// Columns gathered together by State::permute: each thread gathers its share of the slots of a
/// group of columns into as many scratch columns, then one thread swaps each column with its
/// scratch. Two barriers per group (not three per column: 30 columns, 90 barriers, which made
/// much of a rebuild's sort; bench/results/design_measurements.csv).
constexpr size_t kGroup = 4;

/// Gathers the columns by `order`, as many at a time as there are scratch columns (called by
/// every thread of a parallel region).
template <typename T, size_t kScratch>
void apply_order(std::initializer_list<std::vector<T>*> columns, const std::vector<std::int32_t>& order,
                 const std::array<std::vector<T>*, kScratch>& scratch) {
  const long n = static_cast<long>(order.size());
#pragma omp single
  for (std::vector<T>* c : scratch) resize_discarding(*c, order.size());
  for (auto c = columns.begin(); c != columns.end();) {
    std::vector<T>* group[kScratch];
    size_t g = 0;
    for (; g < kScratch && c != columns.end(); ++g, ++c) group[g] = *c;
#pragma omp for schedule(static)
    for (long k = 0; k < n; ++k)
      for (size_t q = 0; q < g; ++q) (*scratch[q])[k] = (*group[q])[order[k]];
#pragma omp single
    for (size_t q = 0; q < g; ++q) {
      group[q]->swap(*scratch[q]);
      resize_discarding(*scratch[q], order.size());  // it now holds a column as it was
    }
  }
}

template <typename T>
void apply_order(std::vector<T>& column, const std::vector<std::int32_t>& order, std::vector<T>& scratch) {
  apply_order({&column}, order, std::array<std::vector<T>*, 1>{&scratch});
}
/// Same for the mesh-contact columns: `per_slot` entries for each of a particle's kSlots slots,
/// of which only the first used[p] hold a contact (the rest are never read, so not copied).
template <typename T>
void apply_order_slots(std::vector<T>& column, const std::vector<std::int32_t>& order, const std::vector<std::uint8_t>& used,
                       size_t per_slot, std::vector<T>& scratch) {
  const size_t stride = MeshContacts::kSlots * per_slot;
  if (stride == 0) return;
#pragma omp single
  resize_discarding(scratch, order.size() * stride);
  const long n = static_cast<long>(order.size());
#pragma omp for schedule(static)
  for (long k = 0; k < n; ++k) {
    const size_t from = static_cast<size_t>(order[k]);
    std::copy_n(column.data() + from * stride, used[from] * per_slot, scratch.data() + k * stride);
  }
#pragma omp single
  column.swap(scratch);
}
template <typename T>
void keep_only_strided(std::vector<T>& column, const std::vector<std::uint8_t>& keep, size_t stride) {
  if (stride == 0) return;
  size_t out = 0;
  for (size_t k = 0; k < keep.size(); ++k)
    if (keep[k]) std::copy_n(column.begin() + static_cast<std::ptrdiff_t>(k * stride), stride, column.begin() + static_cast<std::ptrdiff_t>(out++ * stride));
  column.resize(out * stride);
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
  body.push_back(-1);
  attached.push_back(-1);
  if (has_offsets()) offset_x.push_back(0.0), offset_y.push_back(0.0), offset_z.push_back(0.0);
  MeshContacts& mc = mesh_contacts;
  if (!has_meshes) return x.size() - 1;
  mc.count.push_back(0);
  for (int k = 0; k < MeshContacts::kSlots; ++k) {
    mc.mesh.push_back(-1), mc.triangle.push_back(-1);
    mc.px.push_back(0.0), mc.py.push_back(0.0), mc.pz.push_back(0.0);
  }
  mc.history.resize(mc.history.size() + MeshContacts::kSlots * mesh_history_width, 0.0);
  return x.size() - 1;
}

std::size_t State::add_body(double px, double py, double pz, const double q[4], double m, const double principal[3]) {
  Bodies& b = bodies;
  b.x.push_back(px), b.y.push_back(py), b.z.push_back(pz);
  for (auto* c : {&b.vx, &b.vy, &b.vz, &b.lx, &b.ly, &b.lz, &b.fx, &b.fy, &b.fz, &b.tx, &b.ty, &b.tz}) c->push_back(0.0);
  b.qw.push_back(q[0]), b.qx.push_back(q[1]), b.qy.push_back(q[2]), b.qz.push_back(q[3]);
  b.mass.push_back(m);
  b.ix.push_back(principal[0]), b.iy.push_back(principal[1]), b.iz.push_back(principal[2]);
  b.id.push_back(next_id++);
  return b.size() - 1;
}

void State::attach(std::size_t sphere, std::size_t b, double ox, double oy, double oz) {
  body[sphere] = static_cast<std::int32_t>(b);
  if (!has_offsets())
    for (auto* c : {&offset_x, &offset_y, &offset_z}) c->assign(size(), 0.0);
  offset_x[sphere] = ox, offset_y[sphere] = oy, offset_z[sphere] = oz;
  // Contacts see the body's mass, and a moment of inertia 2/5 m_body r^2 about the sphere's
  // centre (the reduced inertia of rolling resistance, forces.cpp, 7/5 m r^2 about the contact
  // point). A sphere of a body is never integrated on its own.
  inv_mass[sphere] = 1.0 / bodies.mass[b];
  inv_inertia[sphere] = 1.0 / (0.4 * bodies.mass[b] * radius[sphere] * radius[sphere]);
}

std::size_t State::record_size() const {
  return 25 + (has_meshes ? 1 + MeshContacts::kSlots * (5 + mesh_history_width) : 0);
}

void State::pack(std::size_t p, std::vector<double>& out) const {
  for (const auto* c : {&x, &y, &z, &vx, &vy, &vz, &wx, &wy, &wz, &fx, &fy, &fz, &tx, &ty, &tz, &radius, &inv_mass, &inv_inertia})
    out.push_back((*c)[p]);
  for (const auto* c : {&offset_x, &offset_y, &offset_z}) out.push_back(has_offsets() ? (*c)[p] : 0.0);
  out.push_back(material[p]), out.push_back(static_cast<double>(id[p])), out.push_back(body[p]), out.push_back(attached[p]);
  if (!has_meshes) return;
  const MeshContacts& mc = mesh_contacts;
  const size_t slots = MeshContacts::kSlots, first = p * slots;
  out.push_back(mc.count[p]);
  for (size_t k = first; k < first + slots; ++k)
    out.push_back(mc.mesh[k]), out.push_back(mc.triangle[k]), out.push_back(mc.px[k]), out.push_back(mc.py[k]), out.push_back(mc.pz[k]);
  out.insert(out.end(), mc.history.begin() + static_cast<std::ptrdiff_t>(first * mesh_history_width),
             mc.history.begin() + static_cast<std::ptrdiff_t>((first + slots) * mesh_history_width));
}

void State::unpack(const double* in) {
  for (auto* c : {&x, &y, &z, &vx, &vy, &vz, &wx, &wy, &wz, &fx, &fy, &fz, &tx, &ty, &tz, &radius, &inv_mass, &inv_inertia})
    c->push_back(*in++);
  const double* offset = in;
  in += 3;
  material.push_back(static_cast<std::int32_t>(*in++));
  id.push_back(static_cast<std::int64_t>(*in++));
  body.push_back(static_cast<std::int32_t>(*in++));
  attached.push_back(static_cast<std::int32_t>(*in++));
  if (has_offsets() || body.back() >= 0) {
    for (auto* c : {&offset_x, &offset_y, &offset_z}) c->resize(size() - 1, 0.0);  // the first sphere of a body: zeros before it
    offset_x.push_back(offset[0]), offset_y.push_back(offset[1]), offset_z.push_back(offset[2]);
  }
  if (!has_meshes) return;
  MeshContacts& mc = mesh_contacts;
  mc.count.push_back(static_cast<std::uint8_t>(*in++));
  for (int k = 0; k < MeshContacts::kSlots; ++k) {
    mc.mesh.push_back(static_cast<std::int32_t>(in[0])), mc.triangle.push_back(static_cast<std::int32_t>(in[1]));
    mc.px.push_back(in[2]), mc.py.push_back(in[3]), mc.pz.push_back(in[4]);
    in += 5;
  }
  mc.history.insert(mc.history.end(), in, in + MeshContacts::kSlots * mesh_history_width);
}

void State::pack_body(std::size_t k, std::vector<double>& out) const {
  const Bodies& b = bodies;
  for (const auto* c : {&b.x, &b.y, &b.z, &b.vx, &b.vy, &b.vz, &b.qw, &b.qx, &b.qy, &b.qz, &b.lx, &b.ly, &b.lz, &b.fx, &b.fy, &b.fz,
                        &b.tx, &b.ty, &b.tz, &b.mass, &b.ix, &b.iy, &b.iz})
    out.push_back((*c)[k]);
  out.push_back(static_cast<double>(b.id[k]));
}

std::size_t State::unpack_body(const double* in) {
  Bodies& b = bodies;
  for (auto* c : {&b.x, &b.y, &b.z, &b.vx, &b.vy, &b.vz, &b.qw, &b.qx, &b.qy, &b.qz, &b.lx, &b.ly, &b.lz, &b.fx, &b.fy, &b.fz, &b.tx,
                  &b.ty, &b.tz, &b.mass, &b.ix, &b.iy, &b.iz})
    c->push_back(*in++);
  b.id.push_back(static_cast<std::int64_t>(*in));
  return b.size() - 1;
}

void State::permute(const std::vector<std::int32_t>& order, PermuteScratch& scratch) {
  MeshContacts& mc = mesh_contacts;
  // The positions at the last build lend their columns to the gathers (the lists are rebuilt
  // after a permutation, which sets them again): four doubles at a time for 8 bytes of scratch.
  const std::array<std::vector<double>*, kGroup> f64{&scratch.f64, &x_built, &y_built, &z_built};
#pragma omp parallel if (static_cast<long>(order.size()) >= kParallelMin)
  {
    apply_order({&x, &y, &z, &vx, &vy, &vz, &wx, &wy, &wz, &fx, &fy, &fz, &tx, &ty, &tz, &radius, &inv_mass, &inv_inertia},
                order, f64);
    if (has_offsets()) apply_order({&offset_x, &offset_y, &offset_z}, order, f64);
    apply_order({&material, &body, &attached}, order, std::array<std::vector<std::int32_t>*, 1>{&scratch.i32});
    apply_order(id, order, scratch.i64);
    if (has_meshes) {
      for (auto* c : {&mc.mesh, &mc.triangle}) apply_order_slots(*c, order, mc.count, 1, scratch.slots_i32);
      for (auto* c : {&mc.px, &mc.py, &mc.pz}) apply_order_slots(*c, order, mc.count, 1, scratch.slots_f64);
      apply_order_slots(mc.history, order, mc.count, static_cast<size_t>(mesh_history_width), scratch.history);
      apply_order(mc.count, order, scratch.u8);
    }
  }
}

void State::compact(const std::vector<std::uint8_t>& keep) {
  for (auto* c : {&x, &y, &z, &vx, &vy, &vz, &wx, &wy, &wz, &fx, &fy, &fz, &tx, &ty, &tz, &radius, &inv_mass, &inv_inertia})
    keep_only(*c, keep);
  if (has_offsets())
    for (auto* c : {&offset_x, &offset_y, &offset_z}) keep_only(*c, keep);
  keep_only(material, keep);
  keep_only(id, keep);
  keep_only(body, keep);
  keep_only(attached, keep);
  if (has_meshes) {
    MeshContacts& mc = mesh_contacts;
    keep_only(mc.count, keep);
    const size_t slots = MeshContacts::kSlots;
    keep_only_strided(mc.mesh, keep, slots), keep_only_strided(mc.triangle, keep, slots);
    keep_only_strided(mc.px, keep, slots), keep_only_strided(mc.py, keep, slots), keep_only_strided(mc.pz, keep, slots);
    keep_only_strided(mc.history, keep, slots * mesh_history_width);
  }
  if (bodies.size() == 0) return;
  // Remove bodies none of whose spheres remain; renumber the others.
  std::vector<std::uint8_t> body_kept(bodies.size(), 0);
  for (std::int32_t b : body)
    if (b >= 0) body_kept[b] = 1;
  std::vector<std::int32_t> renumber(bodies.size(), -1);
  std::int32_t next = 0;
  for (size_t b = 0; b < bodies.size(); ++b)
    if (body_kept[b]) renumber[b] = next++;
  for (std::int32_t& b : body)
    if (b >= 0) b = renumber[b];
  Bodies& d = bodies;
  for (auto* c : {&d.x, &d.y, &d.z, &d.vx, &d.vy, &d.vz, &d.qw, &d.qx, &d.qy, &d.qz, &d.lx, &d.ly, &d.lz, &d.fx, &d.fy,
                  &d.fz, &d.tx, &d.ty, &d.tz, &d.mass, &d.ix, &d.iy, &d.iz})
    keep_only(*c, body_kept);
  keep_only(d.id, body_kept);
}

}  // namespace dem
