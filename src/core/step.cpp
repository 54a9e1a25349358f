#include "core/step.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "base/parallel.h"
#include "bodies/rigid_body.h"
#include "core/balance.h"
#include "core/domain.h"
#include "core/forces.h"
#include "core/mesh_contacts.h"
#include "core/neighbors.h"
#include "core/particles.h"
#include "core/verlet.h"

namespace dem {

namespace {

/// The opening half kick and the drift in one pass: v += h F/m, w += h T/I, x += dt v for free
/// spheres, and every owned slot's F and T set to zero once used; bodies take the same kick
/// (from their own totals) and move freely, then place their spheres. Returns the
/// Moved flags of the free spheres (the test of needs_rebuild, and that of the near pairs, made
/// while the positions are in cache).
int kick_drift(State& s, Workspace& work, const Model& model, double h, double dt) {
  const long n = static_cast<long>(s.owned());  // ghosts are moved by their owners
  const DriftLimits limits = drift_limits(model, s, work, work.near.valid, s.time + dt);
  int moved = untested(limits);
#pragma omp parallel reduction(| : moved) if (n >= kParallelMin)
  for_own_blocks(work, n, [&](long begin, long end) { moved |= kick_drift_range(s, limits, begin, end, h, dt); });
  Bodies& b = s.bodies;
  if (b.size() == 0) return moved;
  const long nb = static_cast<long>(b.size());
#pragma omp parallel for schedule(static) if (nb >= kParallelMin)
  for (long k = 0; k < nb; ++k) {
    const double a = h / b.mass[k];
    b.vx[k] += a * b.fx[k], b.vy[k] += a * b.fy[k], b.vz[k] += a * b.fz[k];
    b.lx[k] += h * b.tx[k], b.ly[k] += h * b.ty[k], b.lz[k] += h * b.tz[k];
    b.x[k] += dt * b.vx[k], b.y[k] += dt * b.vy[k], b.z[k] += dt * b.vz[k];
    const double momentum[3] = {b.lx[k], b.ly[k], b.lz[k]}, inverse_inertia[3] = {1.0 / b.ix[k], 1.0 / b.iy[k], 1.0 / b.iz[k]};
    const Quaternion q = free_rotation({b.qw[k], b.qx[k], b.qy[k], b.qz[k]}, momentum, inverse_inertia, dt);
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
/// state) against every rank's spheres near the region, and keeps those in its own box.
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

/// One step. `next_follows`: another step follows in the same advance() call, and no one reads
/// or changes the state in between, so this step's closing kick may give that step's opening
/// kick and drift too (ForcePass::drift_ahead: one pass over the spheres less per step, the
/// spheres in cache as their contacts are summed). Without bodies, glued spheres or ranks,
/// whose motion the closing kick does not give. Rejected: the drift inside the next step's
/// contact pass, its flags predicted by the closing kick (a region per step, but the spheres
/// read twice); drifting ahead across calls of step() (the state between steps would not be the
/// state of a time).
void one_step(const Model& model, State& state, Workspace& work, bool next_follows) {
  const double dt = model.dt;
  const int drifted = std::exchange(work.drifted_ahead, -1);
  // Walls and meshes first: what they do does not depend on the spheres' drift.
  move_walls(model, state, dt);
  place_meshes(model, state.time + dt, work);
  const int moved = drifted >= 0 ? drifted : kick_drift(state, work, model, 0.5 * dt, dt);
  const bool free_moved = moved & kRebuild;
  bool rebuilt = false;  // a rebuild may add slots (inlets, migration) whose loads are not zero
  if (work.domain) {
    run_inlets_decomposed(model, state, work);
    // Every rank rebuilds when any must: the ghosts and the pairs across faces change together.
    rebuilt = work.domain->any(free_moved || needs_rebuild(model, state, work, state.time + dt, /*free_spheres_checked=*/true));
    if (rebuilt)
      rebuild_contacts(model, state, work);
    else
      work.domain->refresh_ghosts(state);
  } else {
    for (int k = 0; k < static_cast<int>(model.inlets.size()); ++k)
      if (run_inlet(model, state, k) > 0) work.valid = false;
    rebuilt = free_moved || needs_rebuild(model, state, work, state.time + dt, /*free_spheres_checked=*/true);
    if (rebuilt) rebuild_contacts(model, state, work);
  }
  work.loads_cleared = !rebuilt;
  // The contact pass may read the near pairs alone when the lists were not rebuilt (a rebuild
  // clears near.valid) and no free sphere moved half the margin since the last full scan, or
  // none did from where the lists' common drift carried it (verlet.h, Moved).
  work.near.trusted = !((moved & kRescan) && (moved & kRescanDrift));
  ForcePass pass;
  pass.kick = 0.5 * dt;
  pass.drift_ahead = next_follows && !work.domain && state.bodies.size() == 0 && !model.has_attached;
  compute_forces(model, state, work, pass);
  refresh_body_spheres(model, state, work);
  state.time += dt;
  ++state.step;
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

std::int64_t advance(const Model& model, State& state, Workspace& work, std::int64_t steps) {
  std::int64_t particle_steps = 0;
  for (std::int64_t k = 0; k < steps; ++k) {
    one_step(model, state, work, k + 1 < steps);
    particle_steps += static_cast<std::int64_t>(state.owned());
  }
  return particle_steps;
}

void step(const Model& model, State& state, Workspace& work) { advance(model, state, work, 1); }

}  // namespace dem
