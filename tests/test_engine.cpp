// Engine properties: energy conservation, determinism, contact history across rebuilds and
// re-sorting, particle generation, the time-step advisor.
#include <gtest/gtest.h>

#include <omp.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <set>

#include "core/forces.h"
#include "core/neighbors.h"
#include "core/timestep.h"
#include "sim.h"

namespace dem::test {
namespace {

constexpr double kPi = std::numbers::pi;

/// Kinetic plus Hertz elastic energy 2/5 k delta^(5/2) of every touching contact [J].
double total_energy(const Sim& sim) {
  const State& s = sim.state;
  const Model& m = sim.model;
  double energy = 0;
  for (size_t p = 0; p < s.size(); ++p) {
    energy += 0.5 / s.inv_mass[p] * (s.vx[p] * s.vx[p] + s.vy[p] * s.vy[p] + s.vz[p] * s.vz[p]);
    energy += 0.5 / s.inv_inertia[p] * (s.wx[p] * s.wx[p] + s.wy[p] * s.wy[p] + s.wz[p] * s.wz[p]);
  }
  const double E = m.pair_row(0)[0];
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    const size_t i = s.pairs.i[k], j = s.pairs.j[k];
    const double d = overlap_of(s, i, j);
    const double r = s.radius[i] * s.radius[j] / (s.radius[i] + s.radius[j]);
    if (d > 0) energy += 0.4 * 4.0 / 3.0 * E * std::sqrt(r) * std::pow(d, 2.5);
  }
  for (size_t k = 0; k < s.wall_pairs.size(); ++k) {
    const size_t i = s.wall_pairs.i[k];
    const PlaneWall& w = m.planes[s.wall_pairs.j[k]];
    const double d = s.radius[i] - ((s.x[i] - w.point[0]) * w.normal[0] + (s.y[i] - w.point[1]) * w.normal[1] +
                                    (s.z[i] - w.point[2]) * w.normal[2]);
    if (d > 0) energy += 0.4 * 4.0 / 3.0 * E * std::sqrt(s.radius[i]) * std::pow(d, 2.5);
  }
  return energy;
}

TEST(Energy, ElasticGranularGasConservesEnergyOverManyCollisions) {
  // e = 1, mu = 0, no gravity: velocity Verlet keeps kinetic + elastic energy constant; the
  // drift over thousands of collisions must stay below 1e-3 of the total.
  Sim sim(load_case("elastic_gas.yaml"));
  const double e0 = total_energy(sim);
  std::set<std::pair<std::int64_t, std::int64_t>> touching;
  long collisions = 0;
  double worst = 0;
  while (sim.state.time < 0.25) {
    sim.advance();
    std::set<std::pair<std::int64_t, std::int64_t>> now;
    const State& s = sim.state;
    for (size_t k = 0; k < s.pairs.size(); ++k)
      if (overlap_of(s, s.pairs.i[k], s.pairs.j[k]) > 0)
        now.insert({std::min(s.id[s.pairs.i[k]], s.id[s.pairs.j[k]]), std::max(s.id[s.pairs.i[k]], s.id[s.pairs.j[k]])});
    for (const auto& c : now) collisions += !touching.count(c);
    touching.swap(now);
    if (sim.state.step % 50 == 0) worst = std::max(worst, std::abs(total_energy(sim) - e0) / e0);
  }
  EXPECT_GT(collisions, 2000);
  EXPECT_LT(worst, 1e-3) << collisions << " particle collisions";
}

std::uint64_t settle_hash(int threads, int steps) {
  omp_set_num_threads(threads);
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.particles[0].count = 3000;  // above kParallelMin, so 2 threads really split the loops
  spec.particles[0].region_min.z() = 0.0;  // from the floor up: loose enough to place,
  spec.particles[0].region_max.z() = 0.06;  // dense enough to touch soon
  Sim sim(spec);
  for (int k = 0; k < steps; ++k) sim.advance();
  // The run must reach a bed: spheres touching each other and the walls at the same time.
  EXPECT_GT(sim.work.wall_forces.active.size(), 100u);
  EXPECT_GT(std::count(sim.work.wall_forces.active.begin(), sim.work.wall_forces.active.end(), 1), 100);
  return state_hash(sim.state, sim.model.history_width);
}

TEST(Determinism, SameHashOnRerunAndForOneAndTwoThreads) {
  // Long enough for a bed with particle and wall contacts on the same spheres (the order in
  // which a sphere's contacts are summed must not depend on how threads share the particles).
  const int saved = omp_get_max_threads();
  const std::uint64_t one = settle_hash(1, 3000);
  const std::uint64_t two = settle_hash(2, 3000);
  const std::uint64_t again = settle_hash(2, 3000);
  omp_set_num_threads(saved);
  EXPECT_EQ(two, again) << "rerun";
  EXPECT_EQ(one, two) << "1 versus 2 threads";
}

TEST(Neighbors, HistoryFollowsParticlesThroughRebuildAndResort) {
  // Give every listed contact a history row unique to its particle ids, shuffle the particles'
  // positions in memory by rebuilding after a move, and find each row again by ids.
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.particles[0].count = 3000;
  Sim sim(spec);
  for (int k = 0; k < 200; ++k) sim.advance();  // particles fall, lists are rebuilt and re-sorted
  State& s = sim.state;
  const int width = sim.model.history_width;
  ASSERT_GT(width, 0);
  // The tag is written as seen from the lower id; seen from the higher id the odd history
  // (tangential spring) is negated.
  auto seen_from = [&](std::int64_t i_id, std::int64_t j_id, int q, double tag) {
    return i_id < j_id || !sim.model.history_odd[q] ? tag + q : -(tag + q);
  };
  std::map<std::pair<std::int64_t, std::int64_t>, double> expected;
  size_t swapped = 0;
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    const auto a = s.id[s.pairs.i[k]], b = s.id[s.pairs.j[k]];
    const double tag = 1.0 + static_cast<double>(std::min(a, b) * 100000 + std::max(a, b));
    for (int q = 0; q < width; ++q) s.pairs.history[k * width + q] = seen_from(a, b, q, tag);
    expected[{std::min(a, b), std::max(a, b)}] = tag;
  }
  ASSERT_GT(expected.size(), 100u);
  // Reverse the particles' x order so the cell sort must move nearly every particle.
  for (size_t p = 0; p < s.size(); ++p) s.x[p] = 0.08 - s.x[p];
  rebuild_contacts(sim.model, s, sim.work);
  size_t found = 0;
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    const auto a = s.id[s.pairs.i[k]], b = s.id[s.pairs.j[k]];
    const auto it = expected.find({std::min(a, b), std::max(a, b)});
    if (it == expected.end()) continue;
    ++found;
    swapped += a > b;
    for (int q = 0; q < width; ++q) ASSERT_EQ(s.pairs.history[k * width + q], seen_from(a, b, q, it->second));
  }
  EXPECT_EQ(found, expected.size()) << "every pair still within reach keeps its history";
  EXPECT_GT(swapped, 100u) << "the test must see pairs whose i and j swapped";
}

TEST(Neighbors, NearPairsGiveTheSameRunAsScanningTheWholeList) {
  // The contact pass reads only the pairs within the near margin while no sphere has moved half
  // of it (Workspace::NearPairs). A run that is made to scan the whole list every step must be
  // the same to the last bit: settling spheres with liquid bridges (a range beyond contact) and
  // walls, through free fall, impacts and list rebuilds.
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.particles[0].count = 3000;
  spec.particles[0].region_min.z() = 0.0;  // a packed column: contacts from the first steps
  spec.particles[0].region_max.z() = 0.06;
  Sim near(spec), whole(spec);
  const int steps = 3000;
  const std::int64_t scans_at_start = near.work.near_refreshes;
  for (int k = 0; k < steps; ++k) {
    near.advance();
    whole.work.near.valid = false;  // the next contact pass scans every listed pair
    whole.advance();
  }
  ASSERT_EQ(near.state.size(), whole.state.size());
  EXPECT_EQ(near.work.rebuilds, whole.work.rebuilds);
  EXPECT_EQ(whole.work.near_refreshes - scans_at_start, steps);
  const std::int64_t near_scans = near.work.near_refreshes - scans_at_start;
  EXPECT_LT(near_scans, steps / 2) << "most steps must have read the near pairs alone";
  EXPECT_GE(near.work.rebuilds, 3) << "the run must rebuild its lists";
  size_t touching = 0;
  for (const std::uint8_t a : near.work.pair_forces.active) touching += a;
  EXPECT_GT(touching, 1000u) << "the bed must have settled into contact";
  std::printf("%d steps: %lld full scans, %lld rebuilds, %zu of %zu listed pairs acting\n", steps, static_cast<long long>(near_scans),
              static_cast<long long>(near.work.rebuilds), touching, near.state.pairs.size());
  for (auto column : {&State::x, &State::y, &State::z, &State::vx, &State::vy, &State::vz, &State::wx, &State::wy, &State::wz})
    EXPECT_EQ(near.state.*column, whole.state.*column);
  EXPECT_EQ(near.state.pairs.history, whole.state.pairs.history);
  EXPECT_EQ(near.state.wall_pairs.history, whole.state.wall_pairs.history);
}

/// Net force and torque on each particle by id, evaluated on a copy (the contact histories of
/// `sim` do not advance).
std::map<std::int64_t, std::array<double, 6>> loads_by_id(const Sim& sim) {
  State s = sim.state;
  Workspace work = sim.work;
  compute_forces(sim.model, s, work);
  std::map<std::int64_t, std::array<double, 6>> out;
  for (size_t p = 0; p < s.size(); ++p) out[s.id[p]] = {s.fx[p], s.fy[p], s.fz[p], s.tx[p], s.ty[p], s.tz[p]};
  return out;
}

TEST(Neighbors, ReSortingTheSlotsDoesNotChangeAnyForce) {
  // A sheared, settling bed with loaded tangential springs. Relabel the slots in reverse order
  // (a consistent relabelling: the lists follow) and rebuild: the stable cell sort now puts the
  // spheres of each cell the other way round, so i and j of many pairs swap. The physics must
  // not notice: every force and torque as before (to rounding; the summation order changes).
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.particles[0].count = 3000;
  spec.particles[0].region_min.z() = 0.0;
  spec.particles[0].region_max.z() = 0.06;
  Sim sim(spec);
  for (int k = 0; k < 2000; ++k) sim.advance();
  rebuild_contacts(sim.model, sim.state, sim.work);
  State& s = sim.state;
  const auto before = loads_by_id(sim);
  const size_t n = s.size();
  std::vector<std::int32_t> order(n), new_slot(n);
  for (size_t k = 0; k < n; ++k) order[k] = static_cast<std::int32_t>(n - 1 - k), new_slot[n - 1 - k] = static_cast<std::int32_t>(k);
  s.permute(order);
  for (auto* list : {&s.pairs, &s.wall_pairs})
    for (size_t k = 0; k < list->size(); ++k) list->i[k] = new_slot[list->i[k]];
  for (size_t k = 0; k < s.pairs.size(); ++k) s.pairs.j[k] = new_slot[s.pairs.j[k]];
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> i_before;
  for (size_t k = 0; k < s.pairs.size(); ++k) i_before[{s.id[s.pairs.i[k]], s.id[s.pairs.j[k]]}] = 1;
  rebuild_contacts(sim.model, s, sim.work);
  size_t swapped_loaded = 0;
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    const auto a = s.id[s.pairs.i[k]], b = s.id[s.pairs.j[k]];
    if (i_before.count({b, a}) && sim.work.pair_forces.active[k]) ++swapped_loaded;
  }
  ASSERT_GT(swapped_loaded, 10u) << "touching pairs whose i and j swapped";
  const auto after = loads_by_id(sim);
  double scale = 0, worst = 0;
  for (const auto& [id, load] : before)
    for (int a = 0; a < 3; ++a) scale = std::max(scale, std::abs(load[a]));
  for (const auto& [id, load] : before) {
    const auto& other = after.at(id);
    for (int a = 0; a < 3; ++a) worst = std::max(worst, std::abs(load[a] - other[a]));
  }
  EXPECT_LT(worst, 1e-9 * scale) << "largest force change " << worst << " N of forces up to " << scale << " N";
}

TEST(Neighbors, ARebuildThatDropsSpheresKeepsEveryColumnWithItsSphere) {
  // Spheres that left the domain are dropped by the rebuild's sort, which gathers the columns
  // a few at a time: every column must come out as long as the others, and each slot's values
  // must be those of the sphere with its id.
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.particles[0].count = 3000;  // above kParallelMin: the gathers are shared by the threads
  spec.simulation.has_domain = true;
  spec.simulation.domain_min = {-1, -1, -1}, spec.simulation.domain_max = {1, 1, 1};
  Sim sim(spec);
  for (int k = 0; k < 200; ++k) sim.advance();
  State& s = sim.state;
  for (size_t p = 0; p < s.size(); p += 97) s.x[p] = 1e3;  // far outside the domain
  std::map<std::int64_t, std::array<double, 6>> by_id;
  for (size_t p = 0; p < s.size(); ++p)
    if (s.x[p] < 1e3) by_id[s.id[p]] = {s.y[p], s.vz[p], s.wx[p], s.radius[p], s.inv_mass[p], static_cast<double>(s.material[p])};
  const std::int64_t lost_before = s.lost;
  rebuild_contacts(sim.model, s, sim.work);
  EXPECT_EQ(s.lost - lost_before, 31);
  ASSERT_EQ(s.size(), by_id.size());
  for (const auto* c : {&s.x, &s.y, &s.z, &s.vx, &s.vy, &s.vz, &s.wx, &s.wy, &s.wz, &s.fx, &s.fy, &s.fz, &s.tx, &s.ty, &s.tz,
                        &s.radius, &s.inv_mass, &s.inv_inertia})
    EXPECT_EQ(c->size(), s.size());
  // Free spheres only: no clump offsets held (24 bytes a particle).
  for (const auto* c : {&s.offset_x, &s.offset_y, &s.offset_z}) EXPECT_TRUE(c->empty());
  for (const auto* c : {&s.material, &s.body, &s.attached}) EXPECT_EQ(c->size(), s.size());
  EXPECT_EQ(s.id.size(), s.size());
  size_t wrong = 0;
  for (size_t p = 0; p < s.size(); ++p)
    wrong += by_id.at(s.id[p]) != std::array<double, 6>{s.y[p], s.vz[p], s.wx[p], s.radius[p], s.inv_mass[p], static_cast<double>(s.material[p])};
  EXPECT_EQ(wrong, 0u) << "slots whose values are not their sphere's";
}

/// Pairs of spheres closer than their radii plus `range` (checked against all pairs), and how many
/// of them the pair list lacks: {acting, missing}.
std::pair<size_t, size_t> pairs_acting_and_missing(const State& s, double range) {
  std::set<std::pair<std::int32_t, std::int32_t>> listed;
  for (size_t q = 0; q < s.pairs.size(); ++q) listed.insert({s.pairs.i[q], s.pairs.j[q]});
  size_t acting = 0, missing = 0;
  for (size_t i = 0; i < s.size(); ++i)
    for (size_t j = i + 1; j < s.size(); ++j) {
      const double dx = s.x[i] - s.x[j], dy = s.y[i] - s.y[j], dz = s.z[i] - s.z[j], cut = s.radius[i] + s.radius[j] + range;
      if (dx * dx + dy * dy + dz * dz >= cut * cut) continue;
      ++acting;
      missing += !listed.count({static_cast<std::int32_t>(i), static_cast<std::int32_t>(j)});
    }
  return {acting, missing};
}

/// The elastic gas without its box, all of it moving at u [m/s] along x besides its own motion.
CaseSpec gas_cloud(double u) {
  CaseSpec spec = load_case("elastic_gas.yaml");
  spec.planes.clear();
  for (ParticleSetSpec& set : spec.particles) set.velocity.x() += u;
  return spec;
}

TEST(Neighbors, ListsThatFollowTheCommonDriftStayCompleteAndAreRebuiltAsAtRest) {
  // With static walls the lists follow the spheres' common drift (DriftLimits, verlet.h): only
  // the spheres' motion relative to it uses up the skin. The elastic gas without its box, once at
  // rest as a whole and once flying at 5 m/s, must be rebuilt about as often, less than half as
  // often as |d| <= skin/2 would ask for the flight alone, and its pair list must hold every
  // pair within reach at every step (checked against all 79,800 pairs).
  Sim rest(gas_cloud(0.0)), flying(gas_cloud(5.0));
  ASSERT_TRUE(lists_follow_drift(flying.model, flying.work));
  const int steps = 1500;
  const std::int64_t rest_before = rest.work.rebuilds, flying_before = flying.work.rebuilds;
  size_t missing = 0, touching = 0;
  for (int k = 0; k < steps; ++k) {
    rest.advance(), flying.advance();
    const auto [acting, lacking] = pairs_acting_and_missing(flying.state, flying.model.interaction_range);
    touching += acting, missing += lacking;
  }
  const std::int64_t at_rest = rest.work.rebuilds - rest_before, flown = flying.work.rebuilds - flying_before;
  const double travel = 5.0 * steps * flying.model.dt;  // [m]
  std::printf("%d steps, %.3g m flown: %lld rebuilds flying, %lld at rest; %zu contacts seen, %zu missing\n", steps, travel,
              static_cast<long long>(flown), static_cast<long long>(at_rest), touching, missing);
  EXPECT_GT(touching, 500u) << "the gas must collide";
  EXPECT_EQ(missing, 0u) << "contacts missing from the pair list";
  // The two runs part ways at the first collisions (rounding), so their counts differ a little.
  EXPECT_LE(flown, at_rest * 3 / 2 + 2) << "the flight rebuilds about as often as the cloud at rest";
  EXPECT_LT(static_cast<double>(flown), 0.5 * travel / (0.5 * flying.model.skin)) << "far fewer than the flight's skin/2 steps";
}

TEST(Neighbors, NearPairsOfAFlyingCloudFollowTheDriftAndGiveTheRunOfWholeScans) {
  // The near pairs stay complete while every sphere is within half the margin of where it was at
  // the last full scan, or every sphere is within half the margin of where the lists' common
  // drift carried it since (verlet.h, Moved). The elastic gas without its box flying at 5 m/s
  // must give the run of a copy that scans every listed pair at every step, to the last bit, and
  // its near pairs must cost what they cost the cloud at rest: about as many full scans with as
  // small a margin (with |e| <= margin/2 alone the flight, 0.04 skin a step, needs a full scan
  // every 2 steps at the rest's margin, or a margin three times as wide).
  Sim rest(gas_cloud(0.0)), near(gas_cloud(5.0)), whole(gas_cloud(5.0));
  ASSERT_TRUE(lists_follow_drift(near.model, near.work));
  const int steps = 1500;
  const std::int64_t rest_before = rest.work.near_refreshes, near_before = near.work.near_refreshes;
  double rest_margin = 0.0, near_margin = 0.0;  // [m] summed over the steps
  for (int k = 0; k < steps; ++k) {
    rest.advance(), near.advance();
    whole.work.near.valid = false;  // the next contact pass scans every listed pair
    whole.advance();
    rest_margin += rest.work.near.margin, near_margin += near.work.near.margin;
  }
  const std::int64_t at_rest = rest.work.near_refreshes - rest_before, flying = near.work.near_refreshes - near_before;
  const double skin = near.model.skin;
  std::printf("%d steps: %lld full scans flying, %lld at rest; mean margin %.3g skin flying, %.3g at rest\n", steps,
              static_cast<long long>(flying), static_cast<long long>(at_rest), near_margin / steps / skin, rest_margin / steps / skin);
  for (auto column : {&State::x, &State::y, &State::z, &State::vx, &State::vy, &State::vz, &State::wx, &State::wy, &State::wz})
    EXPECT_EQ(near.state.*column, whole.state.*column);
  EXPECT_EQ(near.state.pairs.history, whole.state.pairs.history);
  EXPECT_LE(flying, at_rest * 5 / 4 + 10) << "the flight scans the whole list about as often as the cloud at rest";
  EXPECT_LE(near_margin, 1.25 * rest_margin) << "with about as small a margin";
}

TEST(Neighbors, ListsThatFollowTheDriftHoldEveryBridgeAndWallOfASettlingBed) {
  // The settling bed (static box, liquid bridges acting beyond contact, rolling resistance):
  // spheres fall, bounce and pack while the lists follow their drift; at every step the pair
  // list must hold every pair closer than the interaction range and the wall list every sphere
  // within it of a wall (checked against all pairs and walls).
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.particles[0].count = 600;
  spec.particles[0].region_min.z() = 0.0;  // a column that falls onto the floor at once
  spec.particles[0].region_max.z() = 0.03;
  Sim sim(spec);
  ASSERT_TRUE(lists_follow_drift(sim.model, sim.work));
  ASSERT_GT(sim.model.interaction_range, 0.0);
  const std::int64_t before = sim.work.rebuilds;
  size_t missing = 0, acting = 0, walls_missing = 0, walls_acting = 0;
  for (int k = 0; k < 4000; ++k) {
    sim.advance();
    const State& s = sim.state;
    const double range = sim.model.interaction_range;
    const auto [pairs_acting, pairs_lacking] = pairs_acting_and_missing(s, range);
    acting += pairs_acting, missing += pairs_lacking;
    std::set<std::pair<std::int32_t, std::int32_t>> listed_walls;
    for (size_t q = 0; q < s.wall_pairs.size(); ++q) listed_walls.insert({s.wall_pairs.i[q], s.wall_pairs.j[q]});
    for (size_t i = 0; i < s.size(); ++i) {
      for (size_t w = 0; w < sim.model.planes.size(); ++w) {
        const double at[3] = {s.walls.px[w], s.walls.py[w], s.walls.pz[w]}, x[3] = {s.x[i], s.y[i], s.z[i]};
        double normal[3];
        const double d = sim.model.planes[w].distance(at, x, normal);
        if (d >= s.radius[i] + range || d <= -s.radius[i]) continue;
        ++walls_acting;
        walls_missing += !listed_walls.count({static_cast<std::int32_t>(i), static_cast<std::int32_t>(w)});
      }
    }
  }
  std::printf("4000 steps: %lld rebuilds; %zu pair and %zu wall interactions seen, %zu and %zu missing\n",
              static_cast<long long>(sim.work.rebuilds - before), acting, walls_acting, missing, walls_missing);
  EXPECT_GT(acting, 100000u) << "the bed must have packed";
  EXPECT_GT(walls_acting, 10000u);
  EXPECT_EQ(missing, 0u);
  EXPECT_EQ(walls_missing, 0u);
}

TEST(Neighbors, ListsOfALargeSparseGridHoldExactlyThePairsAndWallsWithinReach) {
  // A dense bed of 2,500 beads and 500 strays over a box 12 times wider: the grid then has half
  // a million cells, so the cell sort's passes over the cells are shared by the threads; the
  // pair list must hold exactly the pairs closer than the reach (checked against all 4.5
  // million pairs), in rows of ascending partners, and the wall list every sphere by the floor.
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  CaseSpec spec = load_case("settling_bed.yaml");
  std::erase_if(spec.planes, [](const PlaneWallSpec& w) { return w.name != "floor"; });
  spec.particles[0].count = 2500;
  spec.particles[0].region_min = Vec3(0, 0, 0), spec.particles[0].region_max = Vec3(0.08, 0.08, 0.06);
  ParticleSetSpec strays = spec.particles[0];
  strays.count = 500;
  strays.region_min = Vec3(-0.5, -0.5, 0), strays.region_max = Vec3(0.5, 0.5, 0.5);
  spec.particles.push_back(strays);
  Sim sim(spec);
  for (int k = 0; k < 50; ++k) sim.advance();
  rebuild_contacts(sim.model, sim.state, sim.work);
  omp_set_num_threads(saved);
  ASSERT_GT(sim.work.cell_start.size(), 65536u + 2) << "the grid must be large enough for the threads to share its passes";
  const State& s = sim.state;
  const double reach = sim.model.interaction_range + sim.model.skin;
  std::set<std::pair<std::int64_t, std::int64_t>> listed, within;
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    const std::int32_t i = s.pairs.i[k], j = s.pairs.j[k];
    EXPECT_LT(i, j);
    if (k > 0 && s.pairs.i[k - 1] == i) {
      EXPECT_LT(s.pairs.j[k - 1], j) << "partners ascending within a row";
    }
    listed.insert({std::min(s.id[i], s.id[j]), std::max(s.id[i], s.id[j])});
  }
  EXPECT_EQ(listed.size(), s.pairs.size()) << "each pair listed once";
  for (size_t i = 0; i < s.size(); ++i)
    for (size_t j = i + 1; j < s.size(); ++j) {
      const double dx = s.x[i] - s.x[j], dy = s.y[i] - s.y[j], dz = s.z[i] - s.z[j], cut = (s.radius[i] + reach) + s.radius[j];
      if (dx * dx + dy * dy + dz * dz < cut * cut) within.insert({std::min(s.id[i], s.id[j]), std::max(s.id[i], s.id[j])});
    }
  EXPECT_GT(within.size(), 2000u);
  EXPECT_TRUE(listed == within) << listed.size() << " listed, " << within.size() << " within reach";
  size_t by_floor = 0;
  for (size_t p = 0; p < s.size(); ++p) by_floor += s.z[p] < s.radius[p] + reach && s.z[p] > -s.radius[p];
  EXPECT_EQ(s.wall_pairs.size(), by_floor);
  EXPECT_GT(by_floor, 50u);
  for (size_t k = 0; k + 1 < s.wall_pairs.size(); ++k) EXPECT_LT(s.wall_pairs.i[k], s.wall_pairs.i[k + 1]);
}

// The contact kernels see the history as batch columns (effect.h); every effect of the table
// switched on at once must fit them, or compile() refuses the case.
TEST(Effects, EveryEffectTogetherFitsTheBatchHistoryColumns) {
  int width = 0;
  for (const EffectSpec* e : effect_table())
    for (const HistorySpec& h : e->history) width += h.width;
  EXPECT_GT(width, 0);
  EXPECT_LE(width, kHistoryMax);
}

// The particle pairs' geometry leaves the spin inputs (relative spin, reduced moment of
// inertia) unset unless an active effect declares that it reads them (EffectSpec::reads_spin):
// an effect that read them undeclared would see garbage. Each effect is one file of
// src/contact/effects/ (its name its table entry's); the files that index those columns must
// declare it.
TEST(Effects, EffectsThatReadTheSpinInputsDeclareIt) {
  int readers = 0;
  for (const auto& file : std::filesystem::directory_iterator(DEMDESIGN_SOURCE_DIR "/src/contact/effects")) {
    if (file.path().extension() != ".cpp") continue;
    std::ifstream in(file.path());
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    bool reads = false;
    for (const char* column : {"b.wx[", "b.wy[", "b.wz[", "b.inertia_eff["}) reads |= text.find(column) != std::string::npos;
    readers += reads;
    EXPECT_EQ(reads, text.find(".reads_spin = true") != std::string::npos) << file.path() << " reads the spin inputs: declare .reads_spin = true";
  }
  EXPECT_GE(readers, 2) << "the rolling-resistance effects read them";
}

TEST(Particles, DiscreteDistributionHonoursMassFractions) {
  SizeDistributionSpec d;
  d.kind = SizeDistributionSpec::Kind::discrete;
  d.values = {0.002, 0.004, 0.008};
  d.mass_fractions = {0.2, 0.3, 0.5};
  Random random(3);
  std::map<double, double> mass;
  double total = 0;
  for (int k = 0; k < 200000; ++k) {
    const double x = draw_diameter(d, random);
    mass[x] += x * x * x, total += x * x * x;
  }
  for (size_t k = 0; k < d.values.size(); ++k) EXPECT_NEAR(mass[d.values[k]] / total, d.mass_fractions[k], 0.02);
}

TEST(Particles, TruncatedNormalStaysInBoundsWithTheRightMean) {
  SizeDistributionSpec d;
  d.kind = SizeDistributionSpec::Kind::normal;
  d.mean = 0.004, d.std_dev = 0.0005, d.min = 0.003, d.max = 0.005;
  Random random(5);
  double sum = 0;
  for (int k = 0; k < 100000; ++k) {
    const double x = draw_diameter(d, random);
    ASSERT_GE(x, d.min);
    ASSERT_LE(x, d.max);
    sum += x;
  }
  EXPECT_NEAR(sum / 100000, 0.004, 2e-5);
}

TEST(Particles, PlacementIsReproducibleAndWithoutOverlap) {
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.particles[0].count = 3000;
  const Model model = compile(spec);
  const State a = initial_state(model), b = initial_state(model);
  EXPECT_EQ(state_hash(a, 0), state_hash(b, 0));
  Workspace work;
  State s = a;
  rebuild_contacts(model, s, work);
  for (size_t k = 0; k < s.pairs.size(); ++k) ASSERT_LE(overlap_of(s, s.pairs.i[k], s.pairs.j[k]), 0.0);
  spec.simulation.seed = 43;
  EXPECT_NE(state_hash(initial_state(compile(spec)), 0), state_hash(a, 0));
}

TEST(Particles, OverfullRegionIsAClearError) {
  CaseSpec spec = load_case("settling_bed.yaml");
  spec.particles[0].count = 200000;
  try {
    initial_state(compile(spec));
    FAIL() << "expected an error";
  } catch (const CaseError& e) {
    // Refused by compile's volume check before any particle is drawn (or, nearer the limit, by placement).
    EXPECT_NE(std::string(e.what()).find("particles[0]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Enlarge"), std::string::npos) << e.what();
  }
}

TEST(TimeStep, RayleighTimeOfBenchmarkB1) {
  // B1 spec: R = 2 mm, rho 2500, E 5e7, nu 0.25 -> T_R = 7.66e-5 s.
  EXPECT_NEAR(rayleigh_time(0.002, 2500, 5e7, 0.25), 7.66e-5, 0.005 * 7.66e-5);
  // Hertz contact time equals the CO-1 closed form (glass pair): 40.34 us.
  const double m = 2800 * 4.0 / 3.0 * kPi * 1e-6;
  const double e_star = 1.0 / (2 * (1 - 0.04) / 4.8e10);
  EXPECT_NEAR(hertz_contact_time(0.5 * m, 0.005, e_star, 20.0), 40.34e-6, 0.005 * 40.34e-6);
}

TEST(TimeStep, UnsafeStepIsRefusedOrWarnedAsAsked) {
  CaseSpec spec = load_case("hello_sphere.yaml");
  spec.simulation.time_step = 1e-5;  // ~5 x the Rayleigh time of a 4 mm glass bead
  EXPECT_THROW(compile(spec), CaseError);
  spec.simulation.refuse_unsafe_step = false;
  const Model model = compile(spec);
  EXPECT_FALSE(model.advice.safe);
  EXPECT_FALSE(model.notes.empty());
}

TEST(Numerics, BlowUpIsDetectedAndExplained) {
  CaseSpec spec = load_case("hello_sphere.yaml");
  spec.simulation.time_step = 2e-4;  // the bead moves half its radius per step
  spec.simulation.refuse_unsafe_step = false;
  spec.particles[0].velocity = Vec3(0, 0, -10);
  spec.particles[0].positions[0] = Vec3(0, 0, 0.00201);
  Sim sim(spec);
  const std::string trouble = numerical_trouble_within(sim, 100);
  ASSERT_FALSE(trouble.empty()) << "expected numerical trouble";
  EXPECT_NE(trouble.find("particle 0"), std::string::npos) << trouble;
  EXPECT_NE(trouble.find("time step"), std::string::npos) << trouble;
}

}  // namespace
}  // namespace dem::test
