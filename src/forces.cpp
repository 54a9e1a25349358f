// Determinism without atomics or per-contact reaction buffers: the slots (spatially sorted) are
// cut into blocks such that every pair (i, j) has j in i's block or the next (Workspace::block).
// The even blocks are evaluated first, in parallel, then the odd ones: a block's thread adds each
// contact's force to both bodies directly, and no two blocks evaluated at the same time touch the
// same particle. Every particle's sum therefore runs in a fixed order (its own block's pairs in
// list order, and the pairs of the block before it, first or second by the parity of its block)
// that depends on the data only, so the result is bitwise the same for any thread count and
// schedule. Rejected alternatives: atomics or thread-private force arrays (the summation order,
// and so the last bits of every trajectory, would depend on the number of threads); a buffer
// slot per contact summed afterwards (what this engine did first: 48 bytes more per pair each
// step, 1.3x slower on B1).
//
// Sum per particle: particle pairs and plane walls as above, then meshes, then gravity. The
// closing half kick of the step runs in the pass that adds gravity.
#include "parallel.h"
#include "forces.h"

#include "domain.h"
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
  std::int32_t other[kBatch];  // slot of body j (particle pairs)
  bool pair[kBatch];           // particle pair (else plane wall)
  double lever_i[kBatch], lever_j[kBatch];  // [m] centre to contact point
};

void zero_outputs(ContactBatch& b) {
  // One loop over the outputs rather than a memset per column: 17 short memsets cost more in
  // calls than the stores themselves.
  for (int c = 0; c < b.count; ++c) {
    b.fn[c] = b.fn_elastic[c] = b.load[c] = b.kn[c] = b.kt[c] = 0.0;
    b.damp_sn[c] = b.damp_st[c] = b.damp_shape[c] = b.gamma_n[c] = b.gamma_t[c] = 0.0;
    b.ftx[c] = b.fty[c] = b.ftz[c] = b.mx[c] = b.my[c] = b.mz[c] = b.energy_dissipated[c] = 0.0;
  }
}

void set_load(ContactBatch& b) {
  for (int c = 0; c < b.count; ++c) b.load[c] = b.fn[c] > 0.0 ? b.fn[c] : 0.0;
}

/// Evaluates a full batch: adds each contact's force and torque to both bodies' totals and keeps
/// the force on i by contact. Particle and wall contacts share the batch, so each particle's
/// contacts are added in the order they were listed whatever the batch boundaries.
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
      const std::int32_t j = batch.other[c];
      s.fx[j] -= fx, s.fy[j] -= fy, s.fz[j] -= fz;
      s.tx[j] += -batch.lever_j[c] * cx - b.mx[c];
      s.ty[j] += -batch.lever_j[c] * cy - b.my[c];
      s.tz[j] += -batch.lever_j[c] * cz - b.mz[c];
      pf.active[k] = 1;
      pf.fx[k] = fx, pf.fy[k] = fy, pf.fz[k] = fz;
    } else {
      wf.active[k] = 1;
      wf.fx[k] = fx, wf.fy[k] = fy, wf.fz[k] = fz;
    }
  }
  b.count = 0;
}

/// A listed contact that is not acting: inactive, history cleared. Only a contact that was
/// active can have a history (index_contacts marks carried histories active), so idle pairs of
/// the skin cost one byte read.
void forget(ContactList& list, std::uint8_t& active, size_t k, int width) {
  if (!active) return;
  active = 0;
  std::fill_n(&list.history[k * width], width, 0.0);
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

/// The pairs of slot i with partners j in [lo, hi): owned partners in the parallel block pass,
/// ghosts in a pass of their own (a ghost may touch spheres of several blocks).
void particle_contacts(const Model& model, State& s, Workspace& work, Batch& batch, long i, std::int32_t lo, std::int32_t hi) {
  const int width = model.history_width;
  const bool periodic = model.periodic();
  const double range = model.interaction_range;
  ContactBatch& b = batch.b;
  const double xi = s.x[i], yi = s.y[i], zi = s.z[i], ri = s.radius[i];
  for (std::int32_t k = work.pair_begin[i]; k < work.pair_begin[i + 1]; ++k) {
    const std::int32_t j = s.pairs.j[k];
    if (j < lo || j >= hi) continue;
    double d[3] = {xi - s.x[j], yi - s.y[j], zi - s.z[j]};
    if (periodic) minimum_image(model, d);
    const double dx = d[0], dy = d[1], dz = d[2];
    const double dist2 = dx * dx + dy * dy + dz * dz;
    const double reach = ri + s.radius[j] + range;
    if (dist2 >= reach * reach) {
      forget(s.pairs, work.pair_forces.active[k], k, width);
      continue;
    }
    const int c = b.count;
    const double dist = std::sqrt(dist2), inv_dist = 1.0 / dist;
    const double nx = dx * inv_dist, ny = dy * inv_dist, nz = dz * inv_dist;
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
    batch.other[c] = j;
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
  const long n_all = static_cast<long>(s.size());
  const long n = static_cast<long>(s.owned());  // ghosts: forces returned to their owners
  const std::int32_t owned = static_cast<std::int32_t>(n);
  const long block = work.block, blocks = (n + block - 1) / block;
#pragma omp parallel if (n >= kParallelMin)
  {
#pragma omp for schedule(static)
    for (long p = 0; p < n_all; ++p) {
      s.fx[p] = s.fy[p] = s.fz[p] = 0.0;
      s.tx[p] = s.ty[p] = s.tz[p] = 0.0;
    }
    Batch batch;
    batch.b.count = 0;
    for (long parity = 0; parity < 2; ++parity) {
#pragma omp for schedule(dynamic, 1) nowait
      for (long b = parity; b < blocks; b += 2) {
        const long last = std::min(n, (b + 1) * block);
        for (long i = b * block; i < last; ++i) {
          particle_contacts(model, s, work, batch, i, 0, owned);
          wall_contacts(model, s, work, batch, i);
        }
      }
      if (batch.b.count) flush(model, batch, s, work);
#pragma omp barrier
    }
  }
  if (!work.ghost_owners.empty()) {  // pairs with ghosts, in slot order (few: the subdomain's upper face)
    Batch batch;
    batch.b.count = 0;
    for (const std::int32_t i : work.ghost_owners) particle_contacts(model, s, work, batch, i, owned, static_cast<std::int32_t>(n_all));
    if (batch.b.count) flush(model, batch, s, work);
  }

  mesh_contact_forces(model, s, work);
  if (work.domain) work.domain->return_ghost_loads(s);

  // Gravity, and the closing half kick of free spheres.
  const double gx = model.gravity[0], gy = model.gravity[1], gz = model.gravity[2];
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
  for (long p = 0; p < n; ++p) {
    double fx = s.fx[p], fy = s.fy[p], fz = s.fz[p];
    const double tx = s.tx[p], ty = s.ty[p], tz = s.tz[p];
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
    if (work.domain) work.domain->sum_wall_loads(s);
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
