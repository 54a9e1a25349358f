#include "step.h"

#include <algorithm>
#include <cmath>

#include "balance.h"
#include "domain.h"
#include "forces.h"
#include "mesh_contacts.h"
#include "neighbors.h"
#include "parallel.h"
#include "particles.h"
#include "rigid_body.h"

namespace dem {

namespace {

/// What kick_drift found: a free sphere moved more than half the skin since the lists were
/// built (kRebuild), or more than half the near margin since the last full scan (kRescan).
enum Moved : int { kRebuild = 1, kRescan = 2 };

/// kick_drift for the free spheres among slots [begin, end), as a loop the compiler vectorises
/// (spheres of bodies and glued spheres keep their values: their body or wall moves them).
/// Returns the Moved flags: kRebuild checked when kCheck (lists built for these slots), kRescan
/// when kNear (near pairs valid); each flag is set when it is not checked.
template <bool kCheck, bool kNear>
[[gnu::always_inline]] inline int kick_drift_loop(State& s, const Workspace& work, long begin, long end, double h, double dt,
                                                  double limit2, double near2) {
  const std::int32_t *body = s.body.data(), *attached = s.attached.data();
  const double *inv_mass = s.inv_mass.data(), *inv_inertia = s.inv_inertia.data();
  double *fx = s.fx.data(), *fy = s.fy.data(), *fz = s.fz.data();
  double *tx = s.tx.data(), *ty = s.ty.data(), *tz = s.tz.data();
  double *vx = s.vx.data(), *vy = s.vy.data(), *vz = s.vz.data();
  double *wx = s.wx.data(), *wy = s.wy.data(), *wz = s.wz.data();
  double *x = s.x.data(), *y = s.y.data(), *z = s.z.data();
  const double *xb = s.x_built.data(), *yb = s.y_built.data(), *zb = s.z_built.data();
  const double *xn = work.near.x.data(), *yn = work.near.y.data(), *zn = work.near.z.data();
  int moved = (kCheck ? 0 : kRebuild) | (kNear ? 0 : kRescan);
  DEM_VECTOR_LOOP
  for (long p = begin; p < end; ++p) {
    const bool free = (body[p] < 0) & (attached[p] < 0);
    const double a = h * inv_mass[p], b = h * inv_inertia[p];
    const double nvx = vx[p] + a * fx[p], nvy = vy[p] + a * fy[p], nvz = vz[p] + a * fz[p];
    const double nx = x[p] + dt * nvx, ny = y[p] + dt * nvy, nz = z[p] + dt * nvz;
    if constexpr (kCheck) {
      const double dx = nx - xb[p], dy = ny - yb[p], dz = nz - zb[p];
      moved |= (free & (dx * dx + dy * dy + dz * dz > limit2)) * kRebuild;
    }
    if constexpr (kNear) {
      const double ex = nx - xn[p], ey = ny - yn[p], ez = nz - zn[p];
      moved |= (free & (ex * ex + ey * ey + ez * ez > near2)) * kRescan;
    }
    const double nwx = wx[p] + b * tx[p], nwy = wy[p] + b * ty[p], nwz = wz[p] + b * tz[p];
    wx[p] = free ? nwx : wx[p], wy[p] = free ? nwy : wy[p], wz[p] = free ? nwz : wz[p];
    vx[p] = free ? nvx : vx[p], vy[p] = free ? nvy : vy[p], vz[p] = free ? nvz : vz[p];
    x[p] = free ? nx : x[p], y[p] = free ? ny : y[p], z[p] = free ? nz : z[p];
    fx[p] = fy[p] = fz[p] = tx[p] = ty[p] = tz[p] = 0.0;  // used: the contact pass sums anew (Workspace::loads_cleared)
  }
  return moved;
}

DEM_KERNEL int kick_drift_range(State& s, const Workspace& work, long begin, long end, double h, double dt, bool check, bool near,
                                double limit2, double near2) {
  if (check) return near ? kick_drift_loop<true, true>(s, work, begin, end, h, dt, limit2, near2)
                         : kick_drift_loop<true, false>(s, work, begin, end, h, dt, limit2, near2);
  return kick_drift_loop<false, false>(s, work, begin, end, h, dt, limit2, near2);
}

/// The opening half kick and the drift in one pass: v += h F/m, w += h T/I, x += dt v for free
/// spheres, and every owned slot's F and T set to zero once used; bodies take the same kick
/// (from their own totals) and move freely, then place their spheres. Returns the
/// Moved flags of the free spheres (the test of needs_rebuild, and that of the near pairs, made
/// while the positions are in cache).
int kick_drift(State& s, Workspace& work, const Model& model, double h, double dt) {
  const long n = static_cast<long>(s.owned());  // ghosts are moved by their owners
  const bool check = s.x_built.size() == s.size();
  const bool near = check && work.near.valid && work.near.x.size() == static_cast<size_t>(n);
  const double limit2 = 0.25 * model.skin * model.skin, near2 = 0.25 * work.near.margin * work.near.margin;
  int moved = (check ? 0 : kRebuild) | (near ? 0 : kRescan);
#pragma omp parallel reduction(| : moved) if (n >= kParallelMin)
  for_own_blocks(work, n, [&](long begin, long end) {
    moved |= kick_drift_range(s, work, begin, end, h, dt, check, near, limit2, near2);
  });
  Bodies& b = s.bodies;
  if (b.size() == 0) return moved;
  for (size_t k = 0; k < b.size(); ++k) {
    const double a = h / b.mass[k];
    b.vx[k] += a * b.fx[k], b.vy[k] += a * b.fy[k], b.vz[k] += a * b.fz[k];
    b.lx[k] += h * b.tx[k], b.ly[k] += h * b.ty[k], b.lz[k] += h * b.tz[k];
    b.x[k] += dt * b.vx[k], b.y[k] += dt * b.vy[k], b.z[k] += dt * b.vz[k];
    const double momentum[3] = {b.lx[k], b.ly[k], b.lz[k]}, inertia[3] = {b.ix[k], b.iy[k], b.iz[k]};
    const Quaternion q = free_rotation({b.qw[k], b.qx[k], b.qy[k], b.qz[k]}, momentum, inertia, dt);
    b.qw[k] = q.w, b.qx[k] = q.x, b.qy[k] = q.y, b.qz[k] = q.z;
  }
  place_body_spheres(model, s, work.body_begin, work.body_members);
  return moved;
}

/// Walls move at their set velocity; servo walls add the normal speed that drives their
/// stress towards the target: v_n = -clamp((sigma - target)/target, -1, 1) * max_speed.
/// Spheres glued to a wall translate with it (same velocity, same displacement, no spin).
void move_walls(const Model& model, State& s, double h) {
  for (size_t w = 0; w < model.planes.size(); ++w) {
    const PlaneWall& wall = model.planes[w];
    double v[3] = {wall.velocity[0], wall.velocity[1], wall.velocity[2]};
    if (wall.servo) {
      const double stress = -(s.walls.fx[w] * wall.normal[0] + s.walls.fy[w] * wall.normal[1] + s.walls.fz[w] * wall.normal[2]) /
                            wall.servo_area;  // [Pa] compressive
      const double error = std::clamp((stress - wall.target_stress) / wall.target_stress, -1.0, 1.0);
      for (int a = 0; a < 3; ++a) v[a] -= error * wall.servo_max_speed * wall.normal[a];
    }
    s.walls.vx[w] = v[0], s.walls.vy[w] = v[1], s.walls.vz[w] = v[2];
    s.walls.px[w] += h * v[0], s.walls.py[w] += h * v[1], s.walls.pz[w] += h * v[2];
  }
  if (!model.has_attached) return;
  const long n = static_cast<long>(s.size());
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
  for (long p = 0; p < n; ++p) {
    const std::int32_t w = s.attached[p];
    if (w < 0) continue;
    s.vx[p] = s.walls.vx[w], s.vy[p] = s.walls.vy[w], s.vz[p] = s.walls.vz[w];
    s.x[p] += h * s.vx[p], s.y[p] += h * s.vy[p], s.z[p] += h * s.vz[p];
  }
}

/// After the closing kick: sphere velocities of bodies follow the bodies.
void refresh_body_spheres(const Model& model, State& s, const Workspace& work) {
  if (s.bodies.size() > 0) place_body_spheres(model, s, work.body_begin, work.body_members);
}

/// Inlets under domain decomposition: every rank draws the same insertions (same random
/// state) against every rank's spheres near the region, and keeps those in its own slab.
void run_inlets_decomposed(const Model& model, State& state, Workspace& work) {
  Domain& domain = *work.domain;
  for (int k = 0; k < static_cast<int>(model.inlets.size()); ++k) {
    if (!inlet_due(model, state, k)) continue;  // the same on every rank
    drop_ghosts(state);  // new particles go after the owned ones; ghosts come back at the rebuild
    work.valid = false;
    double lo[3], hi[3];
    inlet_reach(model, k, lo, hi);
    const std::vector<std::array<double, 4>> others = domain.particles_in(state, lo, hi);
    const size_t before = state.size();
    if (run_inlet(model, state, k, &others) == 0) continue;
    std::vector<std::uint8_t> keep(state.size(), 1);
    for (size_t p = before; p < state.size(); ++p) {
      const std::int32_t b = state.body[p];  // a clump belongs where its centre is
      keep[p] = b >= 0 ? domain.owns(state.bodies.x[b], state.bodies.y[b], state.bodies.z[b]) : domain.owns(state.x[p], state.y[p], state.z[p]);
    }
    state.compact(keep);
  }
}

}  // namespace

void prepare(const Model& model, State& state, Workspace& work) {
  place_meshes(model, state.time, work);
  if (state.x_built.size() == state.size() && state.size() > 0) {
    index_contacts(model, state, work);  // restored from a checkpoint: keep its lists as they are
    // The checkpoint holds the forces and contact histories; evaluating the contacts on the
    // state itself would advance the histories (tangential springs) a second time and the
    // resumed run would leave the uninterrupted one. Per-contact forces for the workspace
    // (stress tensor, scalars) come from a copy.
    State scratch = state;
    compute_forces(model, scratch, work);
    return;
  }
  rebuild_contacts(model, state, work);
  compute_forces(model, state, work);
}

void step(const Model& model, State& state, Workspace& work) {
  const double dt = model.dt;
  const int moved = kick_drift(state, work, model, 0.5 * dt, dt);
  const bool free_moved = moved & kRebuild;
  move_walls(model, state, dt);
  place_meshes(model, state.time + dt, work);
  bool rebuilt = false;  // a rebuild may add slots (inlets, migration) whose loads are not zero
  if (work.domain) {
    run_inlets_decomposed(model, state, work);
    // Every rank rebuilds when any must: the ghosts and the pairs across faces change together.
    rebuilt = work.domain->any(free_moved || needs_rebuild(model, state, work, /*free_spheres_checked=*/true));
    if (rebuilt)
      rebuild_contacts(model, state, work);
    else
      work.domain->refresh_ghosts(state);
  } else {
    for (int k = 0; k < static_cast<int>(model.inlets.size()); ++k)
      if (run_inlet(model, state, k) > 0) work.valid = false;
    rebuilt = free_moved || needs_rebuild(model, state, work, /*free_spheres_checked=*/true);
    if (rebuilt) rebuild_contacts(model, state, work);
  }
  work.loads_cleared = !rebuilt;
  // The contact pass may read the near pairs alone when the lists were not rebuilt (a rebuild
  // clears near.valid) and no free sphere moved half the margin since the last full scan.
  work.near.trusted = !(moved & kRescan);
  compute_forces(model, state, work, 0.5 * dt);
  refresh_body_spheres(model, state, work);
  state.time += dt;
  ++state.step;
}

}  // namespace dem
