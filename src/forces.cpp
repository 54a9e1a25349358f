// Determinism: a contact's force on body i is added to i's totals by the one thread that owns i,
// in list order; what body j receives is written to the contact's own buffer slot and summed per
// particle afterwards, again in list order. The result is bitwise the same for any thread count
// and schedule. Rejected alternative: atomics or thread-private force arrays; both make the
// summation order (and so the last bits of every trajectory) depend on the number of threads.
//
// Sum per particle, in this order: own pairs (as i), plane walls, meshes, incoming pairs (as j),
// then gravity. The closing half kick of the step runs in the same pass (one sweep over the
// particles instead of two).
#include "parallel.h"
#include "forces.h"

#include "mesh_contacts.h"
#include "neighbors.h"

#include <cmath>
#include <algorithm>
#include <cstring>

namespace dem {

namespace {

/// Per-thread batch plus where each entry goes.
struct Batch {
  ContactBatch b;
  std::int32_t contact[kBatch];
  std::int32_t owner[kBatch];  // slot of body i
  bool pair[kBatch];           // particle pair (else plane wall)
  double lever_i[kBatch], lever_j[kBatch];  // [m] centre to contact point
};

void zero_outputs(ContactBatch& b) {
  const size_t bytes = sizeof(double) * b.count;
  for (double* column : {b.fn, b.fn_elastic, b.load, b.kn, b.kt, b.damp_sn, b.damp_st, b.damp_shape, b.gamma_n,
                         b.gamma_t, b.ftx, b.fty, b.ftz, b.mx, b.my, b.mz, b.energy_dissipated})
    std::memset(column, 0, bytes);
}

void set_load(ContactBatch& b) {
  for (int c = 0; c < b.count; ++c) b.load[c] = b.fn[c] > 0.0 ? b.fn[c] : 0.0;
}

/// Evaluates a full batch: adds each contact's force and torque to body i's totals and keeps
/// the force (and, for particle pairs, the torque on j) in the contact's buffer slot. Particle
/// and wall contacts share the batch, so each particle's contacts are added in the order they
/// were listed whatever the batch boundaries.
void flush(const Model& model, Batch& batch, State& s, Workspace& work) {
  ContactBatch& b = batch.b;
  evaluate_effects(model, b);
  PairForces& pf = work.pair_forces;
  ContactForces& wf = work.wall_forces;
  for (int c = 0; c < b.count; ++c) {
    const std::int32_t k = batch.contact[c], i = batch.owner[c];
    const double nx = b.nx[c], ny = b.ny[c], nz = b.nz[c];
    const double ftx = b.ftx[c], fty = b.fty[c], ftz = b.ftz[c];
    const double fx = b.fn[c] * nx + ftx, fy = b.fn[c] * ny + fty, fz = b.fn[c] * nz + ftz;
    // Torque of the tangential force about each centre: (-lever n) x ft; plus rolling torque.
    const double cx = ny * ftz - nz * fty, cy = nz * ftx - nx * ftz, cz = nx * fty - ny * ftx;  // n x ft
    s.fx[i] += fx, s.fy[i] += fy, s.fz[i] += fz;
    s.tx[i] += -batch.lever_i[c] * cx + b.mx[c];
    s.ty[i] += -batch.lever_i[c] * cy + b.my[c];
    s.tz[i] += -batch.lever_i[c] * cz + b.mz[c];
    if (batch.pair[c]) {
      const std::int32_t q = pf.slot[k];
      pf.active[k] = 1;
      pf.fx[q] = fx, pf.fy[q] = fy, pf.fz[q] = fz;
      pf.tjx[q] = -batch.lever_j[c] * cx - b.mx[c];
      pf.tjy[q] = -batch.lever_j[c] * cy - b.my[c];
      pf.tjz[q] = -batch.lever_j[c] * cz - b.mz[c];
    } else {
      wf.active[k] = 1;
      wf.fx[k] = fx, wf.fy[k] = fy, wf.fz[k] = fz;
    }
  }
  b.count = 0;
}

/// A listed contact that is not acting: inactive, history and kept force cleared. Only a
/// contact that was active can have a history or a force (index_contacts marks carried
/// histories active), so idle pairs of the skin cost one byte read.
void forget(ContactList& list, std::uint8_t& active, size_t k, int width) {
  if (!active) return;
  active = 0;
  std::fill_n(&list.history[k * width], width, 0.0);
}

void forget_pair(State& s, PairForces& pf, size_t k, int width) {
  if (!pf.active[k]) return;
  forget(s.pairs, pf.active[k], k, width);
  const std::int32_t q = pf.slot[k];
  pf.fx[q] = pf.fy[q] = pf.fz[q] = 0.0;
  pf.tjx[q] = pf.tjy[q] = pf.tjz[q] = 0.0;
}

/// Relative-motion columns common to particle and wall contacts.
inline void fill_motion(ContactBatch& b, int c, const State& s, size_t i, double nx, double ny, double nz,
                        double lever_i, double vjx, double vjy, double vjz, double wjx, double wjy, double wjz) {
  // Contact-point velocity of i: v_i + w_i x (-lever_i n).
  const double vix = s.vx[i] - lever_i * (s.wy[i] * nz - s.wz[i] * ny);
  const double viy = s.vy[i] - lever_i * (s.wz[i] * nx - s.wx[i] * nz);
  const double viz = s.vz[i] - lever_i * (s.wx[i] * ny - s.wy[i] * nx);
  const double rx = vix - vjx, ry = viy - vjy, rz = viz - vjz;
  const double vn = rx * nx + ry * ny + rz * nz;
  b.nx[c] = nx, b.ny[c] = ny, b.nz[c] = nz;
  b.vn[c] = vn;
  b.vtx[c] = rx - vn * nx, b.vty[c] = ry - vn * ny, b.vtz[c] = rz - vn * nz;
  b.wx[c] = s.wx[i] - wjx, b.wy[c] = s.wy[i] - wjy, b.wz[c] = s.wz[i] - wjz;
}

void particle_contacts(const Model& model, State& s, Workspace& work, Batch& batch, long i) {
  const int width = model.history_width;
  const bool periodic = model.periodic();
  const double range = model.interaction_range;
  ContactBatch& b = batch.b;
  const double xi = s.x[i], yi = s.y[i], zi = s.z[i], ri = s.radius[i];
  for (std::int32_t k = work.pair_begin[i]; k < work.pair_begin[i + 1]; ++k) {
    const std::int32_t j = s.pairs.j[k];
    double d[3] = {xi - s.x[j], yi - s.y[j], zi - s.z[j]};
    if (periodic) minimum_image(model, d);
    const double dx = d[0], dy = d[1], dz = d[2];
    const double dist2 = dx * dx + dy * dy + dz * dz;
    const double reach = ri + s.radius[j] + range;
    if (dist2 >= reach * reach) {
      forget_pair(s, work.pair_forces, k, width);
      continue;
    }
    const int c = b.count;
    const double dist = std::sqrt(dist2);
    const double nx = dx / dist, ny = dy / dist, nz = dz / dist;
    const double overlap = ri + s.radius[j] - dist;
    const double lever_i = ri - 0.5 * overlap, lever_j = s.radius[j] - 0.5 * overlap;
    // Contact-point velocity of j: v_j + w_j x (lever_j n).
    const double vjx = s.vx[j] + lever_j * (s.wy[j] * nz - s.wz[j] * ny);
    const double vjy = s.vy[j] + lever_j * (s.wz[j] * nx - s.wx[j] * nz);
    const double vjz = s.vz[j] + lever_j * (s.wx[j] * ny - s.wy[j] * nx);
    fill_motion(b, c, s, i, nx, ny, nz, lever_i, vjx, vjy, vjz, s.wx[j], s.wy[j], s.wz[j]);
    b.pair_type[c] = model.pair_type(s.material[i], s.material[j]);
    b.overlap[c] = overlap;
    b.radius_i[c] = ri;
    b.radius_j[c] = s.radius[j];
    b.r_eff[c] = ri * s.radius[j] / (ri + s.radius[j]);
    b.m_eff[c] = 1.0 / (s.inv_mass[i] + s.inv_mass[j]);
    // Moments of inertia about the contact point, 7/5 m R^2 for a sphere.
    b.inertia_eff[c] = 1.0 / (s.inv_mass[i] / (1.4 * ri * ri) + s.inv_mass[j] / (1.4 * s.radius[j] * s.radius[j]));
    b.history[c] = s.pairs.history.data() + static_cast<size_t>(k) * width;
    batch.contact[c] = k;
    batch.owner[c] = static_cast<std::int32_t>(i);
    batch.pair[c] = true;
    batch.lever_i[c] = lever_i;
    batch.lever_j[c] = lever_j;
    if (++b.count == kBatch) flush(model, batch, s, work);
  }
}

void wall_contacts(const Model& model, State& s, Workspace& work, Batch& batch, long i) {
  const int width = model.history_width;
  const double range = model.interaction_range;
  ContactBatch& b = batch.b;
  for (std::int32_t k = work.wall_begin[i]; k < work.wall_begin[i + 1]; ++k) {
    const std::int32_t w = s.wall_pairs.j[k];
    const PlaneWall& wall = model.planes[w];
    const double at[3] = {s.walls.px[w], s.walls.py[w], s.walls.pz[w]}, x[3] = {s.x[i], s.y[i], s.z[i]};
    double normal[3];
    const double dist = wall.distance(at, x, normal);
    const double nx = normal[0], ny = normal[1], nz = normal[2];
    const double overlap = s.radius[i] - dist;
    if (overlap <= -range || dist <= 0.0) {
      forget(s.wall_pairs, work.wall_forces.active[k], k, width);
      continue;
    }
    const int c = b.count;
    fill_motion(b, c, s, i, nx, ny, nz, dist, s.walls.vx[w], s.walls.vy[w], s.walls.vz[w], 0.0, 0.0, 0.0);
    b.pair_type[c] = model.pair_type(s.material[i], wall.material);
    b.overlap[c] = overlap;
    b.radius_i[c] = s.radius[i];
    b.radius_j[c] = 0.0;
    b.r_eff[c] = s.radius[i];
    b.m_eff[c] = 1.0 / s.inv_mass[i];
    b.inertia_eff[c] = 1.4 * s.radius[i] * s.radius[i] / s.inv_mass[i];
    b.history[c] = s.wall_pairs.history.data() + static_cast<size_t>(k) * width;
    batch.contact[c] = k;
    batch.owner[c] = static_cast<std::int32_t>(i);
    batch.pair[c] = false;
    batch.lever_i[c] = dist;
    batch.lever_j[c] = 0.0;
    if (++b.count == kBatch) flush(model, batch, s, work);
  }
}

}  // namespace

void evaluate_effects(const Model& model, ContactBatch& b) {
  zero_outputs(b);
  bool load_set = false;
  for (const ActiveEffect& e : model.effects) {
    if (!load_set && e.spec->stage > Stage::damping) set_load(b), load_set = true;
    const EffectContext ctx{model.pair_table.data(), model.pair_stride, e.param_offset, e.history_offset,
                            e.options.data(), model.dt};
    e.spec->kernel(ctx, b);
  }
  if (!load_set) set_load(b);
}

void compute_forces(const Model& model, State& s, Workspace& work, double kick) {
  const long n = static_cast<long>(s.size());
  // Own contacts. Dynamic chunks: the work per particle varies (a settling bed has all its
  // contacts at the bottom), and the sums do not depend on which thread takes which chunk.
#pragma omp parallel if (n >= kParallelMin)
  {
    Batch batch;
    batch.b.count = 0;
#pragma omp for schedule(dynamic, 256) nowait
    for (long i = 0; i < n; ++i) {
      s.fx[i] = s.fy[i] = s.fz[i] = 0.0;
      s.tx[i] = s.ty[i] = s.tz[i] = 0.0;
      particle_contacts(model, s, work, batch, i);
      wall_contacts(model, s, work, batch, i);
    }
    if (batch.b.count) flush(model, batch, s, work);
  }

  mesh_contact_forces(model, s, work);

  // Incoming pairs (as j, streamed in slot order; idle pairs hold zeros), gravity, and the
  // closing half kick of free spheres.
  const PairForces& pf = work.pair_forces;
  const double gx = model.gravity[0], gy = model.gravity[1], gz = model.gravity[2];
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
  for (long p = 0; p < n; ++p) {
    double fx = s.fx[p], fy = s.fy[p], fz = s.fz[p], tx = s.tx[p], ty = s.ty[p], tz = s.tz[p];
    for (std::int32_t q = work.incoming_begin[p]; q < work.incoming_begin[p + 1]; ++q) {
      fx -= pf.fx[q], fy -= pf.fy[q], fz -= pf.fz[q];
      tx += pf.tjx[q], ty += pf.tjy[q], tz += pf.tjz[q];
    }
    // A body carries its own weight; a glued sphere is part of its wall, which has none.
    const bool free = s.body[p] < 0 && s.attached[p] < 0;
    const double mass = free ? 1.0 / s.inv_mass[p] : 0.0;
    fx += mass * gx, fy += mass * gy, fz += mass * gz;
    s.fx[p] = fx, s.fy[p] = fy, s.fz[p] = fz;
    s.tx[p] = tx, s.ty[p] = ty, s.tz[p] = tz;
    if (free && kick != 0.0) {
      const double a = kick * s.inv_mass[p], b = kick * s.inv_inertia[p];
      s.vx[p] += a * fx, s.vy[p] += a * fy, s.vz[p] += a * fz;
      s.wx[p] += b * tx, s.wy[p] += b * ty, s.wz[p] += b * tz;
    }
  }

  // Bodies: force and torque about the centre of mass from their spheres, plus weight.
  Bodies& bodies = s.bodies;
  const long nb = static_cast<long>(bodies.size());
#pragma omp parallel for schedule(static) if (nb >= kParallelMin)
  for (long b = 0; b < nb; ++b) {
    double fx = bodies.mass[b] * gx, fy = bodies.mass[b] * gy, fz = bodies.mass[b] * gz, tx = 0, ty = 0, tz = 0;
    for (std::int32_t q = work.body_begin[b]; q < work.body_begin[b + 1]; ++q) {
      const std::int32_t p = work.body_members[q];
      const double rx = s.x[p] - bodies.x[b], ry = s.y[p] - bodies.y[b], rz = s.z[p] - bodies.z[b];
      fx += s.fx[p], fy += s.fy[p], fz += s.fz[p];
      tx += s.tx[p] + ry * s.fz[p] - rz * s.fy[p];
      ty += s.ty[p] + rz * s.fx[p] - rx * s.fz[p];
      tz += s.tz[p] + rx * s.fy[p] - ry * s.fx[p];
    }
    bodies.fx[b] = fx, bodies.fy[b] = fy, bodies.fz[b] = fz;
    bodies.tx[b] = tx, bodies.ty[b] = ty, bodies.tz[b] = tz;
    if (kick != 0.0) {
      const double a = kick / bodies.mass[b];
      bodies.vx[b] += a * fx, bodies.vy[b] += a * fy, bodies.vz[b] += a * fz;
      bodies.lx[b] += kick * tx, bodies.ly[b] += kick * ty, bodies.lz[b] += kick * tz;
    }
  }

  // Force on each wall (reaction of its contacts), summed in list order.
  const ContactForces& wf = work.wall_forces;
  for (auto* column : {&s.walls.fx, &s.walls.fy, &s.walls.fz}) std::fill(column->begin(), column->end(), 0.0);
  if (!model.planes.empty()) {
    double* wfx = s.walls.fx.data();
    double* wfy = s.walls.fy.data();
    double* wfz = s.walls.fz.data();
    const std::int32_t* wall = s.wall_pairs.j.data();
    const size_t count = s.wall_pairs.size();
    for (size_t k = 0; k < count; ++k) {
      if (!wf.active[k]) continue;
      const std::int32_t w = wall[k];
      wfx[w] -= wf.fx[k], wfy[w] -= wf.fy[k], wfz[w] -= wf.fz[k];
    }
  }
  // Glued spheres pass their contact forces to their wall, summed in slot order.
  if (!model.has_attached) return;
  for (long p = 0; p < n; ++p) {
    const std::int32_t w = s.attached[p];
    if (w < 0) continue;
    s.walls.fx[w] += s.fx[p], s.walls.fy[w] += s.fy[p], s.walls.fz[w] += s.fz[p];
  }
}

}  // namespace dem
