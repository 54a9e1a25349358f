#include "step.h"

#include "parallel.h"

#include "forces.h"
#include "neighbors.h"

namespace dem {

namespace {

/// v += h F / m, w += h T / I.
void kick(State& s, double h) {
  const long n = static_cast<long>(s.size());
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
  for (long p = 0; p < n; ++p) {
    const double a = h * s.inv_mass[p], b = h * s.inv_inertia[p];
    s.vx[p] += a * s.fx[p], s.vy[p] += a * s.fy[p], s.vz[p] += a * s.fz[p];
    s.wx[p] += b * s.tx[p], s.wy[p] += b * s.ty[p], s.wz[p] += b * s.tz[p];
  }
}

/// x += h v.
void drift(State& s, double h) {
  const long n = static_cast<long>(s.size());
#pragma omp parallel for schedule(static) if (n >= kParallelMin)
  for (long p = 0; p < n; ++p) s.x[p] += h * s.vx[p], s.y[p] += h * s.vy[p], s.z[p] += h * s.vz[p];
}

}  // namespace

void prepare(const Model& model, State& state, Workspace& work) {
  work.valid = false;
  rebuild_contacts(model, state, work);
  compute_forces(model, state, work);
}

void step(const Model& model, State& state, Workspace& work) {
  const double dt = model.dt;
  kick(state, 0.5 * dt);
  drift(state, dt);
  if (needs_rebuild(model, state, work)) rebuild_contacts(model, state, work);
  compute_forces(model, state, work);
  kick(state, 0.5 * dt);
  state.time += dt;
  ++state.step;
}

}  // namespace dem
