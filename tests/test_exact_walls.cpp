// Exact walls beyond the infinite plane and cylinder: discs and tubes (touched from both sides,
// with edges), surfaces that turn (spin), and walls that move far enough to need new lists.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/model.h"
#include "sim.h"

namespace dem::test {
namespace {

PlaneWall round_wall(PlaneWall::Shape shape, double radius, double hole, double length) {
  PlaneWall w{"w", {0, 0, 0}, {0, 0, 1}, {0, 0, 0}, 0};
  w.shape = shape, w.radius = radius, w.hole = hole, w.length = length;
  return w;
}

double distance(const PlaneWall& w, double x, double y, double z, double n[3]) {
  const double at[3] = {0, 0, 0}, p[3] = {x, y, z};
  return w.distance(at, p, n);
}

TEST(ExactWalls, DistanceToADiscAndATubeIsToTheNearestPointOfTheSurface) {
  double n[3];
  // A ring of radii 0.01 and 0.05 m in the plane z = 0: above and below its face, over its hole
  // (to the inner rim), beyond its outer rim (to the rim circle).
  const PlaneWall disc = round_wall(PlaneWall::Shape::disc, 0.05, 0.01, 0);
  EXPECT_DOUBLE_EQ(distance(disc, 0.03, 0, 0.004, n), 0.004);
  EXPECT_DOUBLE_EQ(n[2], 1.0);
  EXPECT_DOUBLE_EQ(distance(disc, 0, 0.03, -0.002, n), 0.002);
  EXPECT_DOUBLE_EQ(n[2], -1.0);
  EXPECT_NEAR(distance(disc, 0.006, 0, 0.003, n), 0.005, 1e-15);  // hypot(0.004, 0.003)
  EXPECT_NEAR(n[0], -0.8, 1e-12);
  EXPECT_NEAR(distance(disc, 0, -0.054, 0.003, n), 0.005, 1e-15);
  EXPECT_NEAR(n[1], -0.8, 1e-12);
  EXPECT_NEAR(n[2], 0.6, 1e-12);
  // A tube of radius 0.04 m from z = 0 to 0.1: inside and outside its side, beyond either rim.
  const PlaneWall tube = round_wall(PlaneWall::Shape::tube, 0.04, 0, 0.1);
  EXPECT_NEAR(distance(tube, 0.03, 0, 0.05, n), 0.01, 1e-15);
  EXPECT_NEAR(n[0], -1.0, 1e-12);
  EXPECT_NEAR(distance(tube, 0, 0.043, 0.05, n), 0.003, 1e-15);
  EXPECT_NEAR(n[1], 1.0, 1e-12);
  EXPECT_NEAR(distance(tube, 0.036, 0, -0.003, n), 0.005, 1e-15);  // below the lower rim
  EXPECT_NEAR(n[2], -0.6, 1e-12);
  EXPECT_NEAR(distance(tube, 0, 0.044, 0.103, n), 0.005, 1e-15);  // above the upper rim, outside
  EXPECT_NEAR(n[1], 0.8, 1e-12);
  // On the axis every point of the side is as near: the distance is the radius.
  EXPECT_NEAR(distance(tube, 0, 0, 0.05, n), 0.04, 1e-15);
}

/// The hello-sphere case: a 4 mm glass bead dropped from 0.1 m onto steel.
CaseSpec bead_on(const PlaneWallSpec& floor) {
  CaseSpec spec = load_case("hello_sphere.yaml");
  spec.planes = {floor};
  return spec;
}

TEST(ExactWalls, ABeadBouncesOnADiscAsOnAPlaneAndFallsPastItsEdge) {
  PlaneWallSpec plane = load_case("hello_sphere.yaml").planes[0];
  PlaneWallSpec disc = plane;
  disc.shape = PlaneWallSpec::Shape::disc, disc.radius = 0.01;
  Sim on_plane(bead_on(plane)), on_disc(bead_on(disc));
  while (on_plane.state.time < 0.3) on_plane.advance(), on_disc.advance();
  // Above the disc's face its distance is the plane's: the same bounces, to the bit.
  EXPECT_EQ(on_disc.state.z[0], on_plane.state.z[0]);
  EXPECT_EQ(on_disc.state.vz[0], on_plane.state.vz[0]);
  EXPECT_GT(on_disc.state.z[0], 0.0);
  // Dropped beside the disc, the bead falls past its edge: free fall, 0.1 m + 0.5 g t^2 below.
  CaseSpec beside = bead_on(disc);
  beside.particles[0].positions[0] = Vec3(0.015, 0, 0.102);
  Sim falling(beside);
  while (falling.state.time < 0.3) falling.advance();
  EXPECT_NEAR(falling.state.z[0], 0.102 - 0.5 * 9.81 * falling.state.time * falling.state.time, 1e-6);
}

TEST(ExactWalls, ATurningCylinderCarriesTheBeadAtItsBottomAtItsSurfaceSpeed) {
  // A bead at the bottom of a drum of radius 0.05 m whose surface turns at 10 rad/s about the
  // axis y: friction brings the contact point to the surface speed, 0.5 m/s along -x
  // (y x -z = -x), and the bead then rolls without slipping.
  CaseSpec spec = load_case("hello_sphere.yaml");
  PlaneWallSpec drum;
  drum.name = "drum", drum.material = "steel", drum.shape = PlaneWallSpec::Shape::cylinder;
  drum.radius = 0.05, drum.point = Vec3::Zero(), drum.normal = Vec3(0, 1, 0), drum.spin = 10.0;
  spec.planes = {drum};
  spec.particles[0].positions[0] = Vec3(0, 0, -0.048);
  Sim sim(spec);
  while (sim.state.time < 0.3) sim.advance();
  const double r = sim.state.radius[0];
  // Contact point (below the centre, n = +z towards the bead): v + w x (-r n).
  const double contact_vx = sim.state.vx[0] - r * sim.state.wy[0];
  EXPECT_NEAR(contact_vx, -0.5, 5e-3);
  // It rocks about the bottom (the impulse that brought it to the surface speed set it rolling
  // at 0.5/3.5 m/s), never far up the wall: within 20 deg of the bottom.
  EXPECT_LT(std::abs(sim.state.x[0]), 0.048 * std::sin(20 * std::numbers::pi / 180));
}

TEST(ExactWalls, AWallMovingFartherThanTheSkinStillMeetsTheBeadsAhead) {
  // No gravity: a bead at rest 20 mm above a floor that rises at 1 m/s. The lists were built with
  // the bead out of the floor's reach; the floor reaches it after 16 mm, many skins later, and
  // must push it, not pass through it.
  CaseSpec spec = load_case("hello_sphere.yaml");
  spec.simulation.gravity = Vec3::Zero();
  spec.simulation.characteristic_velocity = 1.0;
  spec.planes[0].velocity = Vec3(0, 0, 1.0);
  spec.particles[0].positions[0] = Vec3(0, 0, 0.022);
  Sim sim(spec);
  while (sim.state.time < 0.05) sim.advance();
  EXPECT_GT(sim.state.z[0], 0.05 + 0.0019);  // ahead of the floor, now at 0.05 m
  EXPECT_GT(sim.state.vz[0], 1.0);           // struck, moving away at least at the floor's speed
}

}  // namespace
}  // namespace dem::test
