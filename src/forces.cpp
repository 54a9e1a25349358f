// Determinism: each listed contact writes its force into its own buffer slot and each particle
// then sums its contacts in list order, so the result is bitwise the same for any thread count.
// Rejected alternative: atomics or thread-private force arrays; both make the summation order
// (and so the last bits of every trajectory) depend on the number of threads.
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

/// Evaluates a full batch and writes each contact's force and torques to its buffer slot.
void flush(const Model& model, Batch& batch, ContactForces& out) {
  ContactBatch& b = batch.b;
  evaluate_effects(model, b);
  for (int c = 0; c < b.count; ++c) {
    const std::int32_t k = batch.contact[c];
    const double nx = b.nx[c], ny = b.ny[c], nz = b.nz[c];
    const double ftx = b.ftx[c], fty = b.fty[c], ftz = b.ftz[c];
    out.fx[k] = b.fn[c] * nx + ftx;
    out.fy[k] = b.fn[c] * ny + fty;
    out.fz[k] = b.fn[c] * nz + ftz;
    // Torque of the tangential force about each centre: (-lever n) x ft; plus rolling torque.
    const double cx = ny * ftz - nz * fty, cy = nz * ftx - nx * ftz, cz = nx * fty - ny * ftx;  // n x ft
    out.tix[k] = -batch.lever_i[c] * cx + b.mx[c];
    out.tiy[k] = -batch.lever_i[c] * cy + b.my[c];
    out.tiz[k] = -batch.lever_i[c] * cz + b.mz[c];
    out.tjx[k] = -batch.lever_j[c] * cx - b.mx[c];
    out.tjy[k] = -batch.lever_j[c] * cy - b.my[c];
    out.tjz[k] = -batch.lever_j[c] * cz - b.mz[c];
    out.active[k] = 1;
  }
  b.count = 0;
}

void forget(ContactList& list, ContactForces& out, size_t k, int width) {
  out.active[k] = 0;
  double* row = &list.history[k * width];
  for (int q = 0; q < width; ++q) row[q] = 0.0;
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
  for (std::int32_t k = work.pair_begin[i]; k < work.pair_begin[i + 1]; ++k) {
    const std::int32_t j = s.pairs.j[k];
    double d[3] = {s.x[i] - s.x[j], s.y[i] - s.y[j], s.z[i] - s.z[j]};
    if (periodic) minimum_image(model, d);
    const double dx = d[0], dy = d[1], dz = d[2];
    const double dist2 = dx * dx + dy * dy + dz * dz;
    const double reach = s.radius[i] + s.radius[j] + range;
    if (dist2 >= reach * reach) {
      forget(s.pairs, work.pair_forces, k, width);
      continue;
    }
    const int c = b.count;
    const double dist = std::sqrt(dist2);
    const double nx = dx / dist, ny = dy / dist, nz = dz / dist;
    const double overlap = s.radius[i] + s.radius[j] - dist;
    const double lever_i = s.radius[i] - 0.5 * overlap, lever_j = s.radius[j] - 0.5 * overlap;
    // Contact-point velocity of j: v_j + w_j x (lever_j n).
    const double vjx = s.vx[j] + lever_j * (s.wy[j] * nz - s.wz[j] * ny);
    const double vjy = s.vy[j] + lever_j * (s.wz[j] * nx - s.wx[j] * nz);
    const double vjz = s.vz[j] + lever_j * (s.wx[j] * ny - s.wy[j] * nx);
    fill_motion(b, c, s, i, nx, ny, nz, lever_i, vjx, vjy, vjz, s.wx[j], s.wy[j], s.wz[j]);
    b.pair_type[c] = model.pair_type(s.material[i], s.material[j]);
    b.overlap[c] = overlap;
    b.radius_i[c] = s.radius[i];
    b.radius_j[c] = s.radius[j];
    b.r_eff[c] = s.radius[i] * s.radius[j] / (s.radius[i] + s.radius[j]);
    b.m_eff[c] = 1.0 / (s.inv_mass[i] + s.inv_mass[j]);
    // Moments of inertia about the contact point, 7/5 m R^2 for a sphere.
    b.inertia_eff[c] = 1.0 / (s.inv_mass[i] / (1.4 * s.radius[i] * s.radius[i]) +
                              s.inv_mass[j] / (1.4 * s.radius[j] * s.radius[j]));
    b.history[c] = s.pairs.history.data() + static_cast<size_t>(k) * width;
    batch.contact[c] = k;
    batch.lever_i[c] = lever_i;
    batch.lever_j[c] = lever_j;
    if (++b.count == kBatch) flush(model, batch, work.pair_forces);
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
      forget(s.wall_pairs, work.wall_forces, k, width);
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
    batch.lever_i[c] = dist;
    batch.lever_j[c] = 0.0;
    if (++b.count == kBatch) flush(model, batch, work.wall_forces);
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

void compute_forces(const Model& model, State& s, Workspace& work) {
  const long n = static_cast<long>(s.size());
#pragma omp parallel if (n >= kParallelMin)
  {
    Batch batch;
    batch.b.count = 0;
#pragma omp for schedule(static) nowait
    for (long i = 0; i < n; ++i) particle_contacts(model, s, work, batch, i);
    if (batch.b.count) flush(model, batch, work.pair_forces);
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) wall_contacts(model, s, work, batch, i);
    if (batch.b.count) flush(model, batch, work.wall_forces);
  }

  mesh_contact_forces(model, s, work);

  // Sum per particle in list order: own pairs, incoming pairs, walls, meshes; then gravity.
  const ContactForces& mf = work.mesh_forces;
  const bool meshes = !model.meshes.empty();
  const ContactForces& pf = work.pair_forces;
  const ContactForces& wf = work.wall_forces;
  const double gx = model.gravity[0], gy = model.gravity[1], gz = model.gravity[2];
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
  for (long p = 0; p < n; ++p) {
    double fx = 0, fy = 0, fz = 0, tx = 0, ty = 0, tz = 0;
    for (std::int32_t k = work.pair_begin[p]; k < work.pair_begin[p + 1]; ++k) {
      if (!pf.active[k]) continue;
      fx += pf.fx[k], fy += pf.fy[k], fz += pf.fz[k];
      tx += pf.tix[k], ty += pf.tiy[k], tz += pf.tiz[k];
    }
    for (std::int32_t q = work.incoming_begin[p]; q < work.incoming_begin[p + 1]; ++q) {
      const std::int32_t k = work.incoming[q];
      if (!pf.active[k]) continue;
      fx -= pf.fx[k], fy -= pf.fy[k], fz -= pf.fz[k];
      tx += pf.tjx[k], ty += pf.tjy[k], tz += pf.tjz[k];
    }
    for (std::int32_t k = work.wall_begin[p]; k < work.wall_begin[p + 1]; ++k) {
      if (!wf.active[k]) continue;
      fx += wf.fx[k], fy += wf.fy[k], fz += wf.fz[k];
      tx += wf.tix[k], ty += wf.tiy[k], tz += wf.tiz[k];
    }
    if (meshes) {
      for (int k = 0; k < s.mesh_contacts.count[p]; ++k) {
        const size_t slot = static_cast<size_t>(p) * MeshContacts::kSlots + k;
        if (!mf.active[slot]) continue;
        fx += mf.fx[slot], fy += mf.fy[slot], fz += mf.fz[slot];
        tx += mf.tix[slot], ty += mf.tiy[slot], tz += mf.tiz[slot];
      }
    }
    // A body carries its own weight; a glued sphere is part of its wall, which has none.
    const double mass = s.body[p] >= 0 || s.attached[p] >= 0 ? 0.0 : 1.0 / s.inv_mass[p];
    s.fx[p] = fx + mass * gx, s.fy[p] = fy + mass * gy, s.fz[p] = fz + mass * gz;
    s.tx[p] = tx, s.ty[p] = ty, s.tz[p] = tz;
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
  }

  // Force on each wall (reaction of its contacts), summed in list order.
  for (auto* column : {&s.walls.fx, &s.walls.fy, &s.walls.fz}) std::fill(column->begin(), column->end(), 0.0);
  for (size_t k = 0; k < s.wall_pairs.size(); ++k) {
    if (!wf.active[k]) continue;
    const std::int32_t w = s.wall_pairs.j[k];
    s.walls.fx[w] -= wf.fx[k], s.walls.fy[w] -= wf.fy[k], s.walls.fz[w] -= wf.fz[k];
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
