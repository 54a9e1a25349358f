// Periodic boundaries, servo walls, particles glued to walls and the contact stress tensor
// (source paper Eq. 5).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/neighbors.h"
#include "output/checkpoint.h"
#include "sim.h"
#include "statistics/stress.h"

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
  sim.work.keep_pair_forces = true;
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
      across += wrapped * sim.work.pair_forces.force(k, 0) / volume;
    }
  }
  EXPECT_GT(across, 0.05 * all(0, 0)) << "periodic pairs carry a share of the lateral stress";
}

// Particles glued to a plane wall (`attach_to`): the rough plates of the shear cell.

/// A square layer of `per_side`^2 spheres of diameter 4 mm with centres at height `z`, glued to
/// `wall`, as YAML; the 30 mm periodic cell holds 7 a side 4.29 mm apart.
std::string glued_layer(const std::string& wall, double z, int per_side = 7) {
  std::string out = "  - {material: beads, diameter: 0.004, attach_to: " + wall + ", positions: [";
  const double spacing = 0.03 / per_side;
  for (int i = 0; i < per_side; ++i)
    for (int j = 0; j < per_side; ++j)
      out += (i + j ? ", [" : "[") + std::to_string((i + 0.5) * spacing) + ", " + std::to_string((j + 0.5) * spacing) +
             ", " + std::to_string(z) + "]";
  return out + "]}\n";
}

constexpr const char* kGlueCase = R"(
title: glued layer
simulation:
  duration: 1
  gravity: [0, 0, -9.81]
  periodic: [x, y]
  domain: {min: [0, 0, -0.01], max: [0.03, 0.03, 0.06]}
materials:
  beads: {density: 2500, youngs_modulus: 5.0e7, poisson_ratio: 0.25, restitution: 0.3, friction: 0.5}
  plate: {density: 7800, youngs_modulus: 2.0e11, poisson_ratio: 0.3, restitution: 0.3, friction: 0.5}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
)";

TEST(GluedParticles, MoveWithTheirWallAndCarryAParticleRestingOnThem) {
  // A layer glued to a bottom plate that slides along x at 20 mm/s; one free sphere dropped
  // into a hollow of the layer is carried along.
  const std::string text = std::string(kGlueCase) + R"(walls:
  - {name: bottom, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: plate, velocity: [0.02, 0, 0]}
particles:
)" + glued_layer("bottom", 0.002) +
                           "  - {material: beads, diameter: 0.004, positions: [[0.03, 0.03, 0.0049]]}\n";
  Sim sim(parse_case_text(text));
  const size_t n = sim.state.size();
  ASSERT_EQ(n, 50u);
  std::vector<double> x0(n), y0(n), z0(n);  // by id; ids 0..48 are the glued layer
  for (size_t p = 0; p < n; ++p) x0[sim.state.id[p]] = sim.state.x[p], y0[sim.state.id[p]] = sim.state.y[p], z0[sim.state.id[p]] = sim.state.z[p];
  while (sim.state.time < 0.3) sim.advance();
  const State& s = sim.state;
  const double shift = s.walls.px[0];  // the wall's point moved by v t
  EXPECT_NEAR(shift, 0.02 * s.time, 1e-12);
  for (size_t k = 0; k < 49; ++k) {
    const size_t p = sim.slot(static_cast<std::int64_t>(k));
    EXPECT_EQ(s.attached[p], 0);
    double d[3] = {s.x[p] - x0[k] - shift, s.y[p] - y0[k], s.z[p] - z0[k]};
    minimum_image(sim.model, d);
    EXPECT_NEAR(std::abs(d[0]) + std::abs(d[1]) + std::abs(d[2]), 0.0, 1e-12) << "glued sphere " << k;
    EXPECT_EQ(s.vx[p], 0.02);
    EXPECT_EQ(s.vz[p], 0.0);
    EXPECT_EQ(s.wy[p], 0.0);
  }
  // The free sphere sits in its hollow and travels with the plate.
  const size_t free = sim.slot(49);
  EXPECT_EQ(s.attached[free], -1);
  EXPECT_NEAR(s.vx[free], 0.02, 0.02 * 0.01);
  EXPECT_NEAR(s.vz[free], 0.0, 1e-4);
  double rel[3] = {s.x[free] - 0.03 - shift, s.y[free] - 0.03, 0};
  minimum_image(sim.model, rel);
  EXPECT_LT(std::hypot(rel[0], rel[1]), 1e-4) << "stays in its hollow";
  // The plate carries the sphere's weight through its glued layer; glued spheres feel no gravity.
  const double weight = 9.81 / s.inv_mass[free];
  EXPECT_NEAR(s.walls.fz[0], -weight, 0.01 * weight);
  EXPECT_NEAR(s.walls.fx[0], 0.0, 0.01 * weight);
}

TEST(GluedParticles, WallForceIsTheSumOfTheGluedContactForces) {
  // Periodic shear cell in miniature: glued layers on a fixed bottom and a servo top plate that
  // slides; the wall forces equal the contact forces on their glued spheres, pair by pair.
  const std::string text = std::string(kGlueCase) + R"(walls:
  - {name: bottom, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: plate}
  - name: top
    plane: {point: [0, 0, 0.03], normal: [0, 0, -1]}
    material: plate
    servo: {target_stress: 2000, max_speed: 0.05}
    velocity: [0.01, 0, 0]
particles:
)" + glued_layer("bottom", 0.002) + glued_layer("top", 0.028) +
                           "  - {material: beads, diameter: {distribution: uniform, min: 0.0035, max: 0.0045}, count: 150, "
                           "region: {min: [0, 0, 0.0045], max: [0.03, 0.03, 0.0255]}}\n";
  CaseSpec spec = parse_case_text(text);
  spec.simulation.gravity = Vec3::Zero();
  Sim sim(spec);
  sim.work.keep_pair_forces = true;
  while (sim.state.time < 0.4) sim.advance();
  const State& s = sim.state;
  double sum[2][3] = {};  // contact forces on the glued spheres of each wall
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    if (!sim.work.pair_forces.active[k]) continue;
    const double f[3] = {sim.work.pair_forces.force(k, 0), sim.work.pair_forces.force(k, 1), sim.work.pair_forces.force(k, 2)};
    const std::int32_t wi = s.attached[s.pairs.i[k]], wj = s.attached[s.pairs.j[k]];
    EXPECT_FALSE(wi >= 0 && wi == wj) << "no contacts within one glued layer";
    for (int a = 0; a < 3; ++a) {
      if (wi >= 0) sum[wi][a] += f[a];
      if (wj >= 0) sum[wj][a] -= f[a];
    }
  }
  const double scale = 2000.0 * 0.03 * 0.03;  // [N] target load
  for (int w = 0; w < 2; ++w) {
    EXPECT_NEAR(s.walls.fx[w], sum[w][0], 1e-9 * scale);
    EXPECT_NEAR(s.walls.fy[w], sum[w][1], 1e-9 * scale);
    EXPECT_NEAR(s.walls.fz[w], sum[w][2], 1e-9 * scale);
  }
  EXPECT_GT(s.walls.fz[1], 0.5 * scale) << "the servo plate is loaded through its glued layer";
  EXPECT_GT(-s.walls.fx[1], 0.05 * scale) << "and resists the shear";
  for (size_t k = 0; k < s.wall_pairs.size(); ++k) EXPECT_EQ(s.attached[s.wall_pairs.i[k]], -1);
}

TEST(GluedParticles, CheckpointRestartIsBitwise) {
  const std::string text = std::string(kGlueCase) + R"(walls:
  - {name: bottom, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: plate}
  - name: top
    plane: {point: [0, 0, 0.03], normal: [0, 0, -1]}
    material: plate
    servo: {target_stress: 2000, max_speed: 0.05}
    velocity: [0.01, 0, 0]
particles:
)" + glued_layer("bottom", 0.002) + glued_layer("top", 0.028) +
                           "  - {material: beads, diameter: 0.004, count: 120, region: {min: [0, 0, 0.0045], max: [0.03, 0.03, 0.0255]}}\n";
  CaseSpec spec = parse_case_text(text);
  spec.simulation.gravity = Vec3::Zero();
  const std::string dir = (std::filesystem::temp_directory_path() / "demdesign_glued_restart").string();
  std::filesystem::remove_all(dir);
  Sim straight(spec);
  const int steps = static_cast<int>(0.3 / straight.model.dt);  // the sample is loaded and sheared by then
  for (int k = 0; k < steps; ++k) straight.advance();
  EXPECT_GT(straight.state.walls.fz[1], 0.5 * 2000.0 * 0.03 * 0.03);
  Sim first(spec);
  for (int k = 0; k < steps / 2; ++k) first.advance();
  save_checkpoint(dir + "/checkpoint.bin", first.model, first.state);
  Sim second(spec);
  second.state = load_checkpoint(dir + "/checkpoint.bin", second.model);
  second.work = Workspace();
  prepare(second.model, second.state, second.work);
  for (int k = steps / 2; k < steps; ++k) second.advance();
  EXPECT_EQ(second.state.attached, straight.state.attached);
  EXPECT_EQ(state_hash(second.state, second.model.history_width), state_hash(straight.state, straight.model.history_width));
  EXPECT_EQ(second.state.walls.pz[1], straight.state.walls.pz[1]);
  EXPECT_EQ(second.state.walls.fz[1], straight.state.walls.fz[1]);
  std::filesystem::remove_all(dir);
}

TEST(GluedParticles, AttachToNamesAPlaneWall) {
  const std::string text = std::string(kGlueCase) + R"(walls:
  - {name: bottom, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: plate}
particles:
  - {material: beads, diameter: 0.004, attach_to: botom, positions: [[0.01, 0.01, 0.002]]}
)";
  try {
    compile(parse_case_text(text));
    FAIL() << "expected a CaseError";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("attach_to: no wall named 'botom' (did you mean 'bottom'?)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dem::test
