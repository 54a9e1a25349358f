#include "statistics/stress.h"

#include "core/neighbors.h"

#include <stdexcept>

namespace dem {

Eigen::Matrix3d contact_stress(const Model& model, const State& s, const Workspace& work, double volume, bool with_walls) {
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();  // [N m]
  const PairForces& pf = work.pair_forces;
  if (!work.keep_pair_forces || pf.fx.size() != s.pairs.size())
    throw std::logic_error("contact_stress: the pair forces were not kept (set Workspace::keep_pair_forces before the step)");
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    if (!pf.active[k]) continue;
    const size_t i = s.pairs.i[k], j = s.pairs.j[k];
    double d[3] = {s.x[i] - s.x[j], s.y[i] - s.y[j], s.z[i] - s.z[j]};
    minimum_image(model, d);
    const Eigen::Vector3d branch(d[0], d[1], d[2]), force(pf.force(k, 0), pf.force(k, 1), pf.force(k, 2));
    sum += branch * force.transpose();
  }
  if (with_walls) {
    const ContactForces& wf = work.wall_forces;
    for (size_t k = 0; k < s.wall_pairs.size(); ++k) {
      if (!wf.active[k]) continue;
      const size_t i = s.wall_pairs.i[k];
      const int w = s.wall_pairs.j[k];
      const double at[3] = {s.walls.px[w], s.walls.py[w], s.walls.pz[w]}, x[3] = {s.x[i], s.y[i], s.z[i]};
      double n[3];
      const double dist = model.planes[w].distance(at, x, n);
      const Eigen::Vector3d branch(dist * n[0], dist * n[1], dist * n[2]), force(wf.fx[k], wf.fy[k], wf.fz[k]);
      sum += branch * force.transpose();
    }
  }
  return 0.5 * (sum + sum.transpose()) / volume;
}

}  // namespace dem
