// Periodic boundaries, servo walls and the contact stress tensor (source paper Eq. 5).
#include <gtest/gtest.h>

#include <cmath>

#include "sim.h"
#include "stress.h"

namespace dem::test {
namespace {

TEST(Periodic, GasConservesMomentumAcrossTheBoundaries) {
  // Fully periodic elastic gas with a net drift: particles cross every face many times, collide
  // through the boundaries, and total momentum stays what it was (no walls, no gravity).
  CaseSpec spec = load_case("elastic_gas.yaml");
  spec.planes.clear();
  spec.simulation.has_domain = true;
  spec.simulation.domain_min = Vec3(0, 0, 0);
  spec.simulation.domain_max = Vec3(0.06, 0.06, 0.06);
  spec.simulation.periodic[0] = spec.simulation.periodic[1] = spec.simulation.periodic[2] = true;
  Sim sim(spec);
  auto momentum = [&]() {
    Vec3 p = Vec3::Zero();
    for (size_t k = 0; k < sim.state.size(); ++k)
      p += Vec3(sim.state.vx[k], sim.state.vy[k], sim.state.vz[k]) / sim.state.inv_mass[k];
    return p;
  };
  const Vec3 p0 = momentum();
  const double scale = 200 * 1.05 / sim.state.inv_mass[0];  // sum of |m v| order
  long crossing_contacts = 0;
  while (sim.state.time < 0.2) {
    sim.advance();
    const State& s = sim.state;
    for (size_t k = 0; k < s.pairs.size(); ++k) {
      const size_t i = s.pairs.i[k], j = s.pairs.j[k];
      const double dx = s.x[i] - s.x[j], dy = s.y[i] - s.y[j], dz = s.z[i] - s.z[j];
      const double direct = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (direct > s.radius[i] + s.radius[j] + 0.01 && sim.work.pair_forces.active[k]) ++crossing_contacts;
    }
  }
  EXPECT_GT(crossing_contacts, 20) << "contacts through the periodic boundary";
  EXPECT_NEAR((momentum() - p0).norm(), 0.0, 1e-12 * scale);
  EXPECT_EQ(sim.state.size(), 400u);
  for (size_t k = 0; k < sim.state.size(); ++k) {  // positions wrapped within a skin of the box
    EXPECT_GE(sim.state.x[k], -0.002);
    EXPECT_LE(sim.state.x[k], 0.062);
  }
}

TEST(ServoWall, HoldsItsTargetStressAndTheContactStressTensorAgrees) {
  // Periodic in x and y, bottom plate fixed, top plate servo-controlled to 5 kPa, no gravity.
  Sim sim(load_case("periodic_compression.yaml"));
  while (sim.state.time < 0.35) sim.advance();
  const double area = 0.03 * 0.03;
  const Scalars s = measure(sim.model, sim.state, sim.work);
  const double top = s.wall_normal_force[1] / area, bottom = s.wall_normal_force[0] / area;
  EXPECT_NEAR(top, 5000.0, 0.01 * 5000.0) << "servo settles on its target within 1 %";
  EXPECT_NEAR(bottom, 5000.0, 0.01 * 5000.0) << "static equilibrium: the bottom carries the same";
  // Eq. 5 over the sample between the plates: sigma_zz equals the plate stress (3 %).
  const double volume = area * (sim.state.walls.pz[1] - sim.state.walls.pz[0]);
  const Eigen::Matrix3d all = contact_stress(sim.model, sim.state, sim.work, volume);
  EXPECT_NEAR(all(2, 2), 0.5 * (top + bottom), 0.03 * 5000.0);
  EXPECT_GT(all(0, 0), 0.0);  // lateral stress of a confined sample is compressive
  EXPECT_LT(all(0, 0), all(2, 2));
  // The pair-only tensor must count pairs across the periodic boundaries: walls carry no
  // lateral branch vector, so its sigma_xx equals the full one; without the periodic pairs
  // it would be far lower.
  const Eigen::Matrix3d pairs = contact_stress(sim.model, sim.state, sim.work, volume, false);
  EXPECT_NEAR(pairs(0, 0), all(0, 0), 1e-9 * all(0, 0));
  double across = 0;  // sigma_xx of the pairs that touch through a periodic boundary
  const State& st = sim.state;
  for (size_t k = 0; k < st.pairs.size(); ++k) {
    if (!sim.work.pair_forces.active[k]) continue;
    const size_t i = st.pairs.i[k], j = st.pairs.j[k];
    const double dx = st.x[i] - st.x[j], dy = st.y[i] - st.y[j];
    if (std::abs(dx) > 0.015 || std::abs(dy) > 0.015) {
      const double wrapped = dx - 0.03 * std::nearbyint(dx / 0.03);
      across += wrapped * sim.work.pair_forces.fx[k] / volume;
    }
  }
  EXPECT_GT(across, 0.05 * all(0, 0)) << "periodic pairs carry a share of the lateral stress";
}

}  // namespace
}  // namespace dem::test
