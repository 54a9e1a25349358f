// Mesh walls against analytic planes: the failures users of other DEM codes report (bumps at
// shared edges, double forces at vertices, lost contacts) must not happen here.
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>
#include <numeric>
#include <cstdio>

#include "sim.h"

namespace dem::test {
namespace {

/// Rectangle spanned by corner + u + v, split into n x n cells of 2 triangles each (or a fan
/// of `fan` triangles around its centre when fan > 0), normal u x v.
MeshWallSpec rectangle(const std::string& name, const Vec3& corner, const Vec3& u, const Vec3& v, int n, int fan = 0) {
  MeshWallSpec m;
  m.name = name;
  m.material = "steel";
  if (fan > 0) {
    const Vec3 centre = corner + 0.5 * (u + v);
    m.vertices.push_back({centre.x(), centre.y(), centre.z()});
    const Vec3 corners[4] = {corner, corner + u, corner + u + v, corner + v};
    for (int k = 0; k < fan; ++k) {  // points around the rim, walking the rectangle's outline
      const double s = 4.0 * k / fan;
      const int side = static_cast<int>(s);
      const Vec3 p = corners[side] + (s - side) * (corners[(side + 1) % 4] - corners[side]);
      m.vertices.push_back({p.x(), p.y(), p.z()});
    }
    for (int k = 0; k < fan; ++k) m.triangles.push_back({0, 1 + k, 1 + (k + 1) % fan});
    return m;
  }
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const Vec3 p = corner + u * (double(i) / n) + v * (double(j) / n);
      m.vertices.push_back({p.x(), p.y(), p.z()});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  return m;
}

/// The hello-sphere case with its floor plane replaced by a triangulated floor (or kept).
CaseSpec floor_case(bool triangulated, int n = 8, int fan = 0) {
  CaseSpec spec = load_case("hello_sphere.yaml");
  if (triangulated) {
    spec.planes.clear();
    spec.meshes.push_back(rectangle("floor", Vec3(-0.05, -0.05, 0), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0), n, fan));
  }
  return spec;
}

TEST(MeshWalls, BouncingOnATriangulatedBoxEqualsAnalyticPlanes) {
  // A sphere thrown obliquely with spin bounces around a closed box: 6 planes versus 6 faces of
  // 8 x 8 x 2 triangles each. Trajectories agree to 1e-6 (relative to the box size).
  CaseSpec planes = load_case("elastic_gas.yaml");
  planes.particles.resize(1);
  planes.particles[0].count = 0;
  planes.particles[0].positions = {Vec3(0.013, 0.021, 0.037)};
  planes.particles[0].velocity = Vec3(0.9, -0.7, 0.4);
  planes.particles[0].angular_velocity = Vec3(30, 10, -20);
  for (auto& m : planes.materials) m.params["friction"] = 0.3, m.params["restitution"] = 0.8;
  planes.simulation.gravity = Vec3(0, 0, -9.81);
  CaseSpec mesh = planes;
  mesh.planes.clear();
  const double L = 0.06;
  auto face = [&](const std::string& name, Vec3 corner, Vec3 u, Vec3 v) {
    MeshWallSpec m = rectangle(name, corner, u, v, 8);
    m.material = "elastic";
    mesh.meshes.push_back(m);
  };
  face("floor", Vec3(0, 0, 0), Vec3(L, 0, 0), Vec3(0, L, 0));
  face("top", Vec3(0, 0, L), Vec3(0, L, 0), Vec3(L, 0, 0));
  face("x0", Vec3(0, 0, 0), Vec3(0, L, 0), Vec3(0, 0, L));
  face("x1", Vec3(L, 0, 0), Vec3(0, 0, L), Vec3(0, L, 0));
  face("y0", Vec3(0, 0, 0), Vec3(0, 0, L), Vec3(L, 0, 0));
  face("y1", Vec3(0, L, 0), Vec3(L, 0, 0), Vec3(0, 0, L));
  Sim a(planes), b(mesh);
  int contacts_seen = 0;
  while (a.state.time < 0.4) {
    a.advance();
    b.advance();
    contacts_seen += b.state.mesh_contacts.count[0] > 0;
    ASSERT_LE(b.state.mesh_contacts.count[0], 3) << "at most three faces at a corner";
  }
  EXPECT_GT(contacts_seen, 100);
  EXPECT_NEAR(b.state.x[0], a.state.x[0], 1e-6 * L);
  EXPECT_NEAR(b.state.y[0], a.state.y[0], 1e-6 * L);
  EXPECT_NEAR(b.state.z[0], a.state.z[0], 1e-6 * L);
  EXPECT_NEAR(b.state.vx[0], a.state.vx[0], 1e-6);
  EXPECT_NEAR(b.state.wz[0], a.state.wz[0], 1e-4);
}

TEST(MeshWalls, SlidingAndRollingAcrossSharedEdgesFeelsThePlane) {
  // A sphere launched sliding along the floor (friction turns it into rolling) crosses many
  // shared edges and vertices of a 20 x 20 grid: its kinetic energy history equals that on the
  // analytic plane, the vertical force never bumps, and it never has more than one contact.
  for (int fan : {0, 6}) {
    CaseSpec a_spec = floor_case(false), b_spec = floor_case(true, 20, fan);
    for (CaseSpec* s : {&a_spec, &b_spec}) {
      s->particles[0].positions[0] = Vec3(-0.04, -0.03, 0.002 - 1.2e-7);  // resting overlap, nearly
      s->particles[0].velocity = Vec3(0.5, 0.37, 0);
      if (fan) s->particles[0].positions[0] = Vec3(-0.0002, 0.0001, 0.002 - 1.2e-7), s->particles[0].velocity = Vec3(0.01, -0.005, 0);
    }
    for (CaseSpec* s : {&a_spec, &b_spec})
      for (auto& m : s->materials) m.params["restitution"] = 0.3;  // settles quickly
    Sim a(a_spec), b(b_spec);
    const double weight = 9.81 / b.state.inv_mass[0];
    // Settle vertically first (both the same way), then launch.
    const Vec3 launch = a_spec.particles[0].velocity;
    for (Sim* sim : {&a, &b}) {
      for (int k = 0; k < 20000; ++k) {
        sim->advance();
        sim->state.vx[0] = sim->state.vy[0] = 0;
        sim->state.wx[0] = sim->state.wy[0] = sim->state.wz[0] = 0;
      }
      sim->state.vx[0] = launch.x(), sim->state.vy[0] = launch.y();
    }
    double worst_energy = 0, worst_bump = 0;
    for (int k = 0; k < 100000; ++k) {
      a.advance();
      b.advance();
      const Scalars sa = measure(a.model, a.state, a.work), sb = measure(b.model, b.state, b.work);
      const double ea = sa.kinetic_translation + sa.kinetic_rotation, eb = sb.kinetic_translation + sb.kinetic_rotation;
      worst_energy = std::max(worst_energy, std::abs(ea - eb) / std::max(ea, 1e-30));
      worst_bump = std::max(worst_bump, std::abs(b.state.fz[0] - a.state.fz[0]) / weight);
      ASSERT_LE(b.state.mesh_contacts.count[0], 1) << "fan " << fan << " step " << k;
    }
    EXPECT_LT(worst_energy, 1e-6) << "fan " << fan;
    EXPECT_LT(worst_bump, 1e-6) << "fan " << fan;
    EXPECT_NEAR(b.state.x[0], a.state.x[0], 1e-8) << "fan " << fan;
  }
}

// A sphere driven into a triangulated floor at a step far too large for the contact: the
// numerical-trouble check names the mesh, as it names a plane wall or a particle pair.
TEST(MeshWalls, ASphereSunkIntoAMeshIsNumericalTroubleThatNamesTheMesh) {
  CaseSpec spec = floor_case(true);
  spec.simulation.time_step = 2e-4;
  spec.simulation.refuse_unsafe_step = false;
  spec.particles[0].velocity = Vec3(0, 0, -8);  // 80 % of the radius in the first step
  spec.particles[0].positions[0] = Vec3(0.001, 0.002, 0.00201);
  Sim sim(spec);
  const std::string trouble = numerical_trouble_within(sim, 100);
  ASSERT_FALSE(trouble.empty()) << "expected numerical trouble";
  EXPECT_NE(trouble.find("particle 0 overlaps mesh 'floor'"), std::string::npos) << trouble;
  EXPECT_NE(trouble.find("time step"), std::string::npos) << trouble;
}

TEST(MeshWalls, ConvexRidgeGivesOneContactAlongTheEdge) {
  // Two faces meeting at a ridge along y (roof, 30 degree slopes); a sphere resting exactly
  // above the ridge touches the edge once, pushed straight up.
  CaseSpec spec = floor_case(false);
  spec.planes.clear();
  const double s = std::sin(std::numbers::pi / 6), c = std::cos(std::numbers::pi / 6);
  spec.meshes.push_back(rectangle("left", Vec3(-0.05 * c, -0.05, -0.05 * s), Vec3(0.05 * c, 0, 0.05 * s), Vec3(0, 0.1, 0), 4));
  spec.meshes.push_back(rectangle("right", Vec3(0, -0.05, 0), Vec3(0.05 * c, 0, -0.05 * s), Vec3(0, 0.1, 0), 4));
  spec.particles[0].positions[0] = Vec3(0, 0.0013, 0.002 - 1e-7);
  spec.particles[0].velocity = Vec3::Zero();
  spec.simulation.gravity = Vec3(0, 0, -9.81);
  Sim sim(spec);
  sim.advance();
  int contacts = 0;
  for (int k = 0; k < sim.state.mesh_contacts.count[0]; ++k) ++contacts;
  EXPECT_EQ(contacts, 1);
  EXPECT_NEAR(sim.state.fx[0], 0.0, 1e-9);
  EXPECT_GT(sim.state.fz[0] + 9.81 / sim.state.inv_mass[0], 0.0);
}

TEST(MeshWalls, ConcaveCornerEqualsTwoPlanes) {
  // Floor and a wall at x = 0, each triangulated; a sphere pressed into the corner by tilted
  // gravity feels exactly the two analytic planes.
  CaseSpec planes = floor_case(false);
  planes.planes.push_back(PlaneWallSpec{"wall", Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3::Zero(), false, {}, "steel", {}});
  planes.simulation.gravity = Vec3(-3.0, 0, -9.81);
  planes.particles[0].positions[0] = Vec3(0.0021, 0.0003, 0.0021);
  for (auto& m : planes.materials) m.youngs_modulus = 1e8, m.params["restitution"] = 0.3;  // settles fast
  CaseSpec mesh = planes;
  mesh.planes.clear();
  mesh.meshes.push_back(rectangle("floor", Vec3(0, -0.05, 0), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0), 7));
  mesh.meshes.push_back(rectangle("wall", Vec3(0, -0.05, 0), Vec3(0, 0.1, 0), Vec3(0, 0, 0.1), 7));
  Sim a(planes), b(mesh);
  while (a.state.time < 0.1) a.advance(), b.advance();
  EXPECT_EQ(b.state.mesh_contacts.count[0], 2);
  EXPECT_NEAR(b.state.x[0], a.state.x[0], 1e-10);
  EXPECT_NEAR(b.state.z[0], a.state.z[0], 1e-10);
  EXPECT_NEAR(b.state.fx[0], a.state.fx[0], 1e-9);
}

TEST(MeshWalls, BeltSurfaceVelocityDragsAParticleToBeltSpeed) {
  // A static mesh whose surface moves at 1 m/s (a conveyor belt): a bead dropped on it is
  // accelerated by friction until it rolls with the belt, its centre then moving at belt speed.
  CaseSpec spec = floor_case(true, 4);
  spec.meshes[0].surface.kind = SurfaceVelocitySpec::Kind::linear;
  spec.meshes[0].surface.velocity = Vec3(1.0, 0, 0);
  spec.particles[0].positions[0] = Vec3(-0.04, 0, 0.002 - 1e-7);
  spec.particles[0].velocity = Vec3::Zero();
  spec.simulation.gravity = Vec3(0, 0, -9.81);
  Sim sim(spec);
  while (sim.state.time < 0.2) sim.advance();
  // Contact point at rest relative to the belt: v - R w_y = 1 m/s; a rolling ball settles
  // once the slip is gone (Coulomb friction brings the contact point to belt speed).
  EXPECT_NEAR(sim.state.vx[0] - sim.state.radius[0] * sim.state.wy[0], 1.0, 1e-3);
  EXPECT_GT(sim.state.mesh_loads.power[0], -1.0);
}

}  // namespace
}  // namespace dem::test

namespace dem::test {
namespace {

/// Inside of a cylinder (axis z through the origin, radius r, height h) as `segments` x `rings`
/// quads of 2 triangles, normals pointing at the axis.
MeshWallSpec cylinder_mesh(double r, double h, int segments, int rings) {
  MeshWallSpec m;
  m.name = "cylinder";
  m.material = "steel";
  for (int j = 0; j <= rings; ++j)
    for (int i = 0; i < segments; ++i) {
      const double a = 2 * std::numbers::pi * i / segments;
      m.vertices.push_back({r * std::cos(a), r * std::sin(a), h * j / rings});
    }
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < segments; ++i) {
      const int a = j * segments + i, b = j * segments + (i + 1) % segments, c = b + segments, d = a + segments;
      m.triangles.push_back({a, c, b});  // inward normal
      m.triangles.push_back({a, d, c});
    }
  return m;
}

/// Settles 600 beads in the cylinder (analytic or faceted); returns {floor, side} normal force [N]
/// and the beads' weight.
struct BedLoads {
  double floor, side, weight;
};

BedLoads settle_in_cylinder(bool faceted, std::uint64_t seed) {
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.simulation.seed = seed;
  spec.contact.extra.clear();
  spec.contact.rolling.model = "none";
  for (auto& m : spec.materials) m.params.erase("liquid_content"), m.params.erase("rolling_friction");
  spec.planes.resize(1);  // the floor
  if (faceted) {
    spec.meshes.push_back(cylinder_mesh(0.025, 0.15, 96, 12));
  } else {
    PlaneWallSpec side;
    side.name = "side";
    side.shape = PlaneWallSpec::Shape::cylinder;
    side.radius = 0.025;
    side.normal = Vec3(0, 0, 1);
    side.material = "steel";
    spec.planes.push_back(side);
  }
  spec.particles[0].count = 600;
  spec.particles[0].region_min = Vec3(-0.017, -0.017, 0.005);
  spec.particles[0].region_max = Vec3(0.017, 0.017, 0.07);
  Sim sim(spec);
  while (sim.state.time < 0.3) sim.advance();
  const Scalars sc = measure(sim.model, sim.state, sim.work);
  EXPECT_LT(sc.kinetic_translation, 1e-4);
  BedLoads out{sc.wall_normal_force[0], 0.0, 0.0};
  for (size_t p = 0; p < sim.state.size(); ++p) out.weight += 9.81 / sim.state.inv_mass[p];
  if (faceted) {
    for (size_t p = 0; p < sim.state.size(); ++p)
      for (int k = 0; k < sim.state.mesh_contacts.count[p]; ++k) out.side += sim.work.mesh_slots.fn[static_cast<size_t>(sim.state.candidate_begin[p]) + k];
  } else {
    for (size_t k = 0; k < sim.state.wall_pairs.size(); ++k)
      if (sim.state.wall_pairs.j[k] == 1 && sim.work.wall_forces.active[k]) {
        const size_t i = sim.state.wall_pairs.i[k];
        const double rho = std::hypot(sim.state.x[i], sim.state.y[i]);
        out.side += -(sim.work.wall_forces.fx[k] * sim.state.x[i] + sim.work.wall_forces.fy[k] * sim.state.y[i]) / rho;
      }
  }
  return out;
}

TEST(MeshWalls, BedInTriangulatedCylinderCarriesTheWallForceOfTheAnalyticCylinder) {
  // 600 beads settle in a cylinder of radius 25 mm: against the analytic cylinder and against
  // 96 x 12 x 2 triangles. The floor carries the weight less what wall friction holds (Janssen);
  // the sum of normal forces on the side wall measures the lateral pressure. The faceted wall is
  // 0.05 % closer to the axis between vertices, so the two must agree to a few percent. One
  // packing's side load scatters by about 10 % (measured: 0.27-0.33 N over four packings), so
  // each geometry is settled from eight packings and the means must agree within 3 % or 2.5
  // standard errors of their difference, whichever is larger.
  const int kSeeds = 8;
  std::vector<double> side_a, side_b;
  double floor_a = 0, floor_b = 0, weight = 0;
  for (int k = 0; k < kSeeds; ++k) {
    const BedLoads a = settle_in_cylinder(false, 11 + k), b = settle_in_cylinder(true, 11 + k);
    side_a.push_back(a.side), side_b.push_back(b.side);
    floor_a += a.floor / kSeeds, floor_b += b.floor / kSeeds, weight += a.weight / kSeeds;
  }
  auto mean = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size()); };
  auto variance_of_mean = [&](const std::vector<double>& v) {
    const double m = mean(v);
    double ss = 0;
    for (double x : v) ss += (x - m) * (x - m);
    return ss / static_cast<double>(v.size() - 1) / static_cast<double>(v.size());
  };
  const double ma = mean(side_a), mb = mean(side_b);
  const double tolerance = std::max(0.03 * ma, 2.5 * std::sqrt(variance_of_mean(side_a) + variance_of_mean(side_b)));
  EXPECT_NEAR(floor_b, floor_a, 0.03 * weight);
  EXPECT_GT(ma, 0.02 * weight);
  EXPECT_NEAR(mb, ma, tolerance);
  EXPECT_LT(tolerance, 0.15 * ma) << "the packings scatter too much for the comparison to mean anything";
  std::printf("floor %.4f / %.4f N, side %.4f / %.4f N (analytic / faceted, means of %d packings, tolerance %.4f N), weight %.4f N\n",
              floor_a, floor_b, ma, mb, kSeeds, tolerance, weight);
}

}  // namespace
}  // namespace dem::test

namespace dem::test {
namespace {

TEST(MeshWalls, RecordedFrictionWorkEqualsCoulombWorkAndImpactsAreCounted) {
  // A bead dropped onto a triangulated floor: one impact, on one triangle, with the energy
  // 1/2 m vn^2 of the impact. Then it is pushed along the floor at constant speed (imposed), so
  // friction works at mu m g v: the recorded shear work over the slide equals mu m g times the
  // distance (1 %).
  CaseSpec spec = floor_case(true, 10);
  for (auto& m : spec.materials) m.youngs_modulus = 1e8, m.params["restitution"] = 0.2, m.params["friction"] = 0.3;
  spec.particles[0].positions[0] = Vec3(0.0012, 0.0013, 0.0025);
  spec.particles[0].velocity = Vec3(0, 0, -0.5);
  Sim sim(spec);
  while (sim.state.time < 0.05) sim.advance();  // lands and settles
  const TriangleRecords& r = sim.state.records[0];
  double impacts = 0, energy = 0;
  for (size_t t = 0; t < r.impacts.size(); ++t) impacts += r.impacts[t], energy += r.impact_energy[t];
  EXPECT_GE(impacts, 1.0);
  EXPECT_LE(impacts, 4.0) << "one impact and a few small rebounds (e = 0.2)";
  const double mass = 1.0 / sim.state.inv_mass[0];
  // The first impact, at about 0.5 m/s, carries nearly all the impact energy; rebounds add e^2.
  EXPECT_GT(energy, 0.9 * 0.5 * mass * 0.5 * 0.5);
  EXPECT_LT(energy, 1.2 * 0.5 * mass * 0.52 * 0.52);
  // Slide at 0.1 m/s for 0.2 s: 20 mm across many triangles.
  double before = 0;
  for (double w : r.shear_work) before += w;
  const double x0 = sim.state.x[0];
  while (sim.state.time < 0.25) {
    sim.state.vx[0] = 0.1, sim.state.vy[0] = 0;
    sim.state.wx[0] = sim.state.wy[0] = sim.state.wz[0] = 0;
    sim.advance();
  }
  double after = 0;
  for (double w : r.shear_work) after += w;
  const double distance = sim.state.x[0] - x0;
  EXPECT_NEAR(after - before, 0.3 * mass * 9.81 * distance, 0.01 * 0.3 * mass * 9.81 * distance);
}

/// The settling bed of 3,000 beads with its floor and one side wall triangulated (two meshes,
/// 16 x 16 x 2 triangles each), recording from the start.
CaseSpec bed_on_meshes_spec() {
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.particles[0].count = 3000;  // above kParallelMin: two threads split the passes
  spec.particles[0].region_min.z() = 0.0;
  spec.particles[0].region_max.z() = 0.06;  // on the floor soon
  std::erase_if(spec.planes, [](const PlaneWallSpec& w) { return w.name == "floor" || w.name == "x0"; });
  const double L = 0.08;
  spec.meshes.push_back(rectangle("floor", Vec3(0, 0, 0), Vec3(L, 0, 0), Vec3(0, L, 0), 16));
  spec.meshes.push_back(rectangle("x0", Vec3(0, 0, 0), Vec3(0, L, 0), Vec3(0, 0, L), 16));
  spec.output.records_from = 0.0;
  return spec;
}

/// That bed after `steps` steps on `threads` threads: every triangle's records and each mesh's
/// loads, in one column, and the hash of the particles.
std::pair<std::vector<double>, std::uint64_t> bed_on_meshes(int threads, int steps) {
  omp_set_num_threads(threads);
  Sim sim(bed_on_meshes_spec());
  for (int k = 0; k < steps; ++k) sim.advance();
  std::vector<double> out;
  for (const TriangleRecords& r : sim.state.records)
    for (const std::vector<double>* c : r.columns()) out.insert(out.end(), c->begin(), c->end());
  const MeshLoads& l = sim.state.mesh_loads;
  for (const auto* c : {&l.fx, &l.fy, &l.fz, &l.tx, &l.ty, &l.tz, &l.power}) out.insert(out.end(), c->begin(), c->end());
  return {out, state_hash(sim.state, sim.model.history_width)};
}

TEST(MeshWalls, RecordsAndLoadsAreBitwiseTheSameOnOneTwoAndThreeThreads) {
  // Each thread sums the records and loads of its own spheres, in turn (forces.cpp): every
  // number must still be summed in slot order, so bitwise that of one thread, however the
  // spheres are shared.
  const int saved = omp_get_max_threads();
  const auto one = bed_on_meshes(1, 4000), two = bed_on_meshes(2, 4000), three = bed_on_meshes(3, 4000);
  omp_set_num_threads(saved);
  size_t touched = 0;
  for (const double v : one.first) touched += v != 0.0;
  EXPECT_GT(touched, 1000u) << "the beads must have loaded many triangles of both meshes";
  for (const auto* other : {&two, &three}) {
    EXPECT_EQ(one.second, other->second);
    ASSERT_EQ(one.first.size(), other->first.size());
    size_t differ = 0;
    for (size_t k = 0; k < one.first.size(); ++k) differ += one.first[k] != other->first[k];
    EXPECT_EQ(differ, 0u) << (other == &two ? "two" : "three") << " threads";
  }
}

/// The bed of bed_on_meshes_spec thrown down, stepped by advance() in calls of `chunk` steps (1: step()). Between
/// calls, every 500 steps, the highest sphere is put 3 mm higher, as a caller of the engine may do.
std::pair<std::uint64_t, Workspace> bed_in_calls(int threads, int steps, int chunk) {
  omp_set_num_threads(threads);
  CaseSpec spec = bed_on_meshes_spec();
  spec.particles[0].velocity = Vec3(0.2, 0.1, -0.5);  // [m/s] thrown at the floor: rebuilds the drift finds
  Sim sim(spec);
  for (int done = 0; done < steps; done += 500) {
    if (chunk == 1)
      for (int k = 0; k < 500; ++k) sim.advance();
    else
      for (int k = 0; k < 500; k += chunk) advance(sim.model, sim.state, sim.work, std::min(chunk, 500 - k));
    const auto p = std::max_element(sim.state.z.begin(), sim.state.z.end()) - sim.state.z.begin();
    sim.state.z[p] += 0.003;  // beyond half the skin: the next step must rebuild the lists
  }
  std::uint64_t hash = state_hash(sim.state, sim.model.history_width);
  for (const TriangleRecords& r : sim.state.records)
    for (const auto* c : {&r.normal_impulse, &r.shear_work, &r.impact_energy})
      for (const double v : *c) hash = hash * 1099511628211ull ^ std::bit_cast<std::uint64_t>(v);
  return {hash, std::move(sim.work)};
}

TEST(Stepping, AdvanceGivesBitwiseTheRunOfSingleSteps) {
  // Within advance() each step's closing kick also gives the next step's opening kick and drift
  // (step.cpp), and the next step rebuilds its lists from the flags that drift found. Spheres
  // thrown onto two meshes, with list rebuilds, rescans of the near pairs and a sphere moved
  // between calls, must give the state and triangle records of step() after step(), bitwise, on
  // 1, 2 and 3 threads.
  const int saved = omp_get_max_threads();
  const auto single = bed_in_calls(2, 2000, 1);
  for (const int threads : {1, 2, 3}) {
    const auto chunked = bed_in_calls(threads, 2000, 10);
    EXPECT_EQ(single.first, chunked.first) << threads << " threads";
    EXPECT_EQ(single.second.rebuilds, chunked.second.rebuilds) << threads << " threads";
    EXPECT_EQ(chunked.second.drifts_ahead, 1800) << "all but the last step of each call drift the next one ahead";
    std::printf("%d threads: %lld of 2000 steps drifted ahead, %lld rebuilds\n", threads,
                static_cast<long long>(chunked.second.drifts_ahead), static_cast<long long>(chunked.second.rebuilds));
  }
  omp_set_num_threads(saved);
  EXPECT_EQ(single.second.drifts_ahead, 0);
  EXPECT_GE(single.second.rebuilds, 10) << "the spheres' motion and each moved sphere must cause rebuilds";
}

// A lid meshed at z = 0 that becomes a wall at 0.3 s (`active_from`), over an analytic floor at
// z = -1 m. Sphere A (from z = 0.1 m) falls through the lid's place before then: at 0.29 s it
// is where free fall puts it, z = 0.1 - g t^2 / 2 (exact under the kick-drift-kick integrator),
// and the lid has felt nothing. Sphere B (from z = 1 m) reaches the lid at 0.45 s, after it
// switched on, and comes to rest on it: its centre one radius above, with the lid carrying its
// weight (5 %), while A lies on the floor below.
TEST(MeshWalls, AMeshSwitchedOnLaterIsPassedThroughBeforeAndHoldsAfter) {
  const CaseSpec spec = parse_case_text(R"(
simulation: {duration: 1.0, time_step: 1.0e-5, gravity: [0, 0, -9.81]}
materials: {beads: {density: 2500, youngs_modulus: 1.0e7, poisson_ratio: 0.25, restitution: 0.2, friction: 0.5}}
contact: {normal: hertz, damping: restitution, tangential: mindlin}
walls: [{name: floor, material: beads, plane: {point: [0, 0, -1], normal: [0, 0, 1]}}]
meshes:
  - name: lid
    material: beads
    vertices: [[-0.5, -0.5, 0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]]
    triangles: [[0, 1, 2], [0, 2, 3]]
    active_from: 0.3
particles:
  - {material: beads, diameter: 0.02, positions: [[-0.2, 0, 0.1], [0.2, 0, 1.0]]}
)");
  Sim sim(spec);
  ASSERT_EQ(sim.model.meshes.size(), 1u);
  EXPECT_EQ(sim.model.meshes[0].active_from, 0.3);
  const size_t a = sim.slot(0), b = sim.slot(1);
  const double g = 9.81, dt = sim.model.dt, r = 0.01;
  double lid_force_before = 0;
  while (sim.state.time < 0.29 - 0.5 * dt) {
    sim.advance();
    lid_force_before = std::max(lid_force_before, std::abs(sim.state.mesh_loads.fz.empty() ? 0.0 : sim.state.mesh_loads.fz[0]));
  }
  const double t = sim.state.time;
  EXPECT_NEAR(sim.state.z[a], 0.1 - 0.5 * g * t * t, 1e-9) << "sphere A must have fallen freely through the lid's place";
  EXPECT_EQ(lid_force_before, 0.0);
  while (sim.state.time < 1.0 - 0.5 * dt) sim.advance();
  const double mass = 2500 * std::numbers::pi / 6 * 0.02 * 0.02 * 0.02;
  EXPECT_NEAR(sim.state.z[b], r, 0.01 * r) << "sphere B rests on the lid";
  EXPECT_NEAR(sim.state.mesh_loads.fz[0], -mass * g, 0.05 * mass * g) << "the lid carries B's weight";
  EXPECT_NEAR(sim.state.z[a], -1 + r, 0.01 * r) << "sphere A lies on the floor";
}

}  // namespace
}  // namespace dem::test
