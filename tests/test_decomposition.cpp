// The geometry and rules of the domain decomposition (src/core/decomposition.h) in one process,
// without MPI: the rank grid chosen for 2 to 8 ranks, the cuts at quantiles of the work, which
// box owns a point on, near and across a cut and a period, which neighbours receive a particle
// as a ghost near a face, an edge and a corner, and when the cuts move. The split runs of
// test_domain_mpi.cpp check the transport around these; here each number is worked out by hand
// beside its check.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <set>
#include <vector>

#include "core/decomposition.h"

namespace dem {
namespace {

constexpr bool kNoPeriod[3] = {false, false, false};

/// A model with no gravity, no domain box and no period: what the tests below set is all there is.
Model plain_model() {
  Model model;
  model.gravity = {0.0, 0.0, 0.0};
  return model;
}

/// Free spheres of 0.1 mm at (x, 0, 0), in the order given.
State spheres_along_x(const std::vector<double>& xs) {
  State s;
  for (double x : xs) s.add_sphere(x, 0.0, 0.0, 1e-4, 1000.0, 0);
  return s;
}

/// 1,000 coordinates evenly in [0, 1] m, one every millimetre ((i + 0.5) mm), shuffled (i -> 7 i
/// mod 1000 visits each once, as 7 and 1000 share no factor): the quantiles must not depend on
/// the order of the slots.
std::vector<double> thousand_along_x() {
  std::vector<double> xs;
  for (int i = 0; i < 1000; ++i) xs.push_back(((i * 7) % 1000 + 0.5) / 1000.0);
  return xs;
}

/// A grid along x alone: `boxes` boxes, cut at `cuts` [m]; periodic over [low, low + period] when
/// `period` > 0.
BoxGrid grid_along_x(int boxes, const std::vector<double>& cuts, double period = 0.0, double low = 0.0) {
  Model model = plain_model();
  model.period = {period, 0.0, 0.0};
  model.domain_min = {low, 0.0, 0.0};
  BoxGrid grid = box_grid({boxes, 1, 1}, model, 0.01);
  grid.cuts[0] = cuts;
  return grid;
}

using Offsets = std::set<std::array<int, 3>>;

/// The offsets of the lower neighbours in `around` that receive a particle at `at` of the box
/// [lo, hi] as a ghost.
Offsets receivers(const Neighbourhood& around, const double at[3], const double lo[3], const double hi[3], double reach) {
  Offsets out;
  for (const NeighbourBox& n : around.lower)
    if (near_shared_boundary(n.offset, at, lo, hi, reach)) out.insert(std::array<int, 3>{n.offset.d[0], n.offset.d[1], n.offset.d[2]});
  return out;
}

// ---------------------------------------------------------------------------------------------
// The grid

TEST(Decomposition, GridSharesTheLeastFaceArea) {
  // A bed 4 x 2 x 1 m. Across a cut axis an outer box of two has one face, an interior box two;
  // the score is the busiest box's shared area (faces x the box's cross-section):
  //   2 ranks: 2x1x1 shares 1 x (2 x 1) = 2 m^2; 1x2x1 shares 4, 1x1x2 8.
  //   4 ranks: 2x2x1 shares 1 x 1 + 1 x 2 = 3 m^2; 4x1x1 (interior boxes) 2 x 2 = 4.
  //   6 ranks: 3x2x1 shares 2 x 1 + 1 x 4/3 = 3.33 m^2; 6x1x1 4, 2x3x1 4.67.
  //   8 ranks: 4x2x1 shares 2 x 1 + 1 x 1 = 3 m^2; 2x2x2 3.5, 8x1x1 and 4x1x2 4.
  const double extent[3] = {4.0, 2.0, 1.0};
  EXPECT_EQ(choose_grid(2, extent, kNoPeriod, 0.1), (std::array<int, 3>{2, 1, 1}));
  EXPECT_EQ(choose_grid(4, extent, kNoPeriod, 0.1), (std::array<int, 3>{2, 2, 1}));
  EXPECT_EQ(choose_grid(6, extent, kNoPeriod, 0.1), (std::array<int, 3>{3, 2, 1}));
  EXPECT_EQ(choose_grid(8, extent, kNoPeriod, 0.1), (std::array<int, 3>{4, 2, 1}));
}

TEST(Decomposition, OfEqualAreasTheGridWithFewerCutAxes) {
  // 3 x 1 x 1 m on 4 ranks: 4x1x1 shares 2 x (1 x 1) = 2 m^2, 2x1x2 1 x 0.5 + 1 x 1.5 = 2 m^2 and
  // 2x2x1 as much; the grid cut along one axis has fewer neighbours and messages.
  const double extent[3] = {3.0, 1.0, 1.0};
  EXPECT_EQ(choose_grid(4, extent, kNoPeriod, 0.1), (std::array<int, 3>{4, 1, 1}));
}

TEST(Decomposition, TheAxisOfGravityCountsHalf) {
  // A domain box of 2 x 1 x 2 m. Gravity along -z: scores 2, 1, 1, and on 2 ranks 2x1x1 shares
  // 1 x 1 = 1 against 2 for the others: the cut stands across x, not across the fall. Gravity
  // along -x: scores 1, 1, 2, and 1x1x2 wins the same way.
  Model model = plain_model();
  model.has_domain = true;
  model.domain_min = {0.0, 0.0, 0.0};
  model.domain_max = {2.0, 1.0, 2.0};
  model.gravity = {0.0, 0.0, -9.81};
  const State none{};
  const GridSpan falling_z = grid_span(model, none);
  EXPECT_EQ(falling_z.extent[0], 2.0);
  EXPECT_EQ(falling_z.extent[2], 2.0);
  EXPECT_EQ(falling_z.score[2], 1.0);
  EXPECT_EQ(choose_grid(2, falling_z.score, falling_z.periodic, 0.1), (std::array<int, 3>{2, 1, 1}));
  model.gravity = {-9.81, 0.0, 0.0};
  const GridSpan falling_x = grid_span(model, none);
  EXPECT_EQ(falling_x.score[0], 1.0);
  EXPECT_EQ(falling_x.score[2], 2.0);
  EXPECT_EQ(choose_grid(2, falling_x.score, falling_x.periodic, 0.1), (std::array<int, 3>{1, 1, 2}));
}

TEST(Decomposition, APeriodicAxisCountsItsPeriodAndTwoFaces) {
  // Periodic along x with a period of 2 m in a domain box 5 m long: the extent is the period. Cut
  // across x, each of two boxes touches the other across both its faces: 2 x (1.5 x 1) = 3 m^2,
  // against 1 x (2 x 1) = 2 m^2 for 1x2x1; without the period 2x1x1 would share 1.5 m^2 and win.
  Model model = plain_model();
  model.has_domain = true;
  model.domain_min = {0.0, 0.0, 0.0};
  model.domain_max = {5.0, 1.5, 1.0};
  model.period = {2.0, 0.0, 0.0};
  const GridSpan span = grid_span(model, State{});
  EXPECT_EQ(span.extent[0], 2.0);
  EXPECT_EQ(span.extent[1], 1.5);
  EXPECT_TRUE(span.periodic[0]);
  EXPECT_FALSE(span.periodic[1]);
  EXPECT_EQ(choose_grid(2, span.score, span.periodic, 0.1), (std::array<int, 3>{1, 2, 1}));
  EXPECT_EQ(choose_grid(2, span.score, kNoPeriod, 0.1), (std::array<int, 3>{2, 1, 1}));
}

TEST(Decomposition, TheParticlesSpanTheGridWhereTheyReachBeyondTheDomainBox) {
  // Particles from x = 0.5 to 2.5 m in a domain box 1 m long: the extent is theirs, 2 m.
  Model model = plain_model();
  model.has_domain = true;
  model.domain_min = {0.0, 0.0, 0.0};
  model.domain_max = {1.0, 1.0, 1.0};
  const GridSpan span = grid_span(model, spheres_along_x({1.0, 0.5, 2.5}));
  EXPECT_EQ(span.extent[0], 2.0);
  EXPECT_EQ(span.extent[1], 1.0);
}

TEST(Decomposition, EveryBoxOfTheGridIsOneReachWide) {
  // 1 m cut into 4: the two interior boxes need 2 x narrowest (the outer ones reach to
  // infinity); periodic, all four need it.
  const double extent[3] = {1.0, 1.0, 1.0};
  const bool periodic_x[3] = {true, false, false};
  EXPECT_TRUE(grid_fits({4, 1, 1}, extent, kNoPeriod, 0.5));
  EXPECT_FALSE(grid_fits({4, 1, 1}, extent, kNoPeriod, 0.51));
  EXPECT_TRUE(grid_fits({4, 1, 1}, extent, periodic_x, 0.25));
  EXPECT_FALSE(grid_fits({4, 1, 1}, extent, periodic_x, 0.26));
  // 3 ranks over 0.1 m boxes one reach of 0.2 m: the middle box of any 3-box axis is too narrow.
  const double small[3] = {0.1, 0.1, 0.1};
  EXPECT_EQ(choose_grid(3, small, kNoPeriod, 0.2), (std::array<int, 3>{0, 0, 0}));
}

TEST(Decomposition, TheGhostReachCoversTheLargestPairAndAClumpsReach) {
  // Reach: 2 x the largest radius (15 mm, larger than the model's 10 mm) + interaction range
  // 1 mm + skin 2 mm = 33 mm. A clump sphere 5 mm (3-4-5) from its centre adds 5 mm to the
  // reach and 5 mm more to the narrowest box: 38 mm and 43 mm.
  Model model = plain_model();
  model.radius_max = 0.010;
  model.interaction_range = 0.001;
  model.skin = 0.002;
  State s;
  s.add_sphere(0.0, 0.0, 0.0, 0.015, 1000.0, 0);
  const GhostReach free_only = ghost_reach(model, s);
  EXPECT_NEAR(free_only.reach, 0.033, 1e-15);
  EXPECT_NEAR(free_only.box_min, 0.033, 1e-15);
  EXPECT_EQ(free_only.sticking_out, 0.0);
  const double q[4] = {1.0, 0.0, 0.0, 0.0}, inertia[3] = {1e-6, 1e-6, 1e-6};
  const size_t body = s.add_body(1.0, 0.0, 0.0, q, 0.01, inertia);
  s.attach(s.add_sphere(1.003, 0.004, 0.0, 0.005, 1000.0, 0), body, 0.003, 0.004, 0.0);
  const GhostReach with_clump = ghost_reach(model, s);
  EXPECT_NEAR(with_clump.sticking_out, 0.005, 1e-15);
  EXPECT_NEAR(with_clump.reach, 0.038, 1e-15);
  EXPECT_NEAR(with_clump.box_min, 0.043, 1e-15);
}

// ---------------------------------------------------------------------------------------------
// Cuts

TEST(Decomposition, FirstCutsAtTheMedianParticle) {
  // 1,000 particles, one a millimetre: the cut between two boxes is the 501st smallest
  // coordinate, 0.5005 m (500 below, 500 at or above); into four, the 251st, 501st and 751st.
  std::vector<double> sorted = thousand_along_x();
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(quantile_cuts(sorted, 2, 0.0, 1.0), (std::vector<double>{sorted[500]}));
  EXPECT_EQ(sorted[500], 0.5005);
  EXPECT_EQ(quantile_cuts(sorted, 4, 0.0, 1.0), (std::vector<double>{sorted[250], sorted[500], sorted[750]}));
  // Fewer particles than boxes: evenly over [lo, hi].
  EXPECT_EQ(quantile_cuts({0.1, 0.2, 0.3}, 4, 0.0, 1.0), (std::vector<double>{0.25, 0.5, 0.75}));

  // The same through first_cuts, with the particles in shuffled slots.
  const Model model = plain_model();
  const State s = spheres_along_x(thousand_along_x());
  BoxGrid grid = box_grid({2, 1, 1}, model, 0.01);
  first_cuts(grid, model, s);
  ASSERT_EQ(grid.cuts[0].size(), 1u);
  EXPECT_EQ(grid.cuts[0][0], 0.5005);
  EXPECT_TRUE(grid.cuts[1].empty());
  EXPECT_TRUE(grid.cuts[2].empty());
  int below = 0;
  for (double x : s.x) below += x < grid.cuts[0][0];
  EXPECT_EQ(below, 500);
}

TEST(Decomposition, FirstCutsOverTheDomainBoxWhenTheBoxesOutnumberTheParticles) {
  // One particle, four boxes along a domain 2 m long: cuts at 0.5, 1 and 1.5 m.
  Model model = plain_model();
  model.has_domain = true;
  model.domain_min = {0.0, 0.0, 0.0};
  model.domain_max = {2.0, 1.0, 1.0};
  BoxGrid grid = box_grid({4, 1, 1}, model, 0.01);
  first_cuts(grid, model, spheres_along_x({0.3}));
  EXPECT_EQ(grid.cuts[0], (std::vector<double>{0.5, 1.0, 1.5}));
}

TEST(Decomposition, CutsAtTheMedianOfTheWorkWithinOneParticle) {
  // 1,000 particles of work 1 each, one a millimetre from 0.5 mm to 999.5 mm: the histogram spans
  // their 0.999 m in 4096 bins of 0.244 mm, each particle alone in its bin. Half the work (500)
  // is reached at the end of the 500th particle's bin (x = 0.4995 m): the cut lies between it and
  // the next (0.5005 m), 500 particles on either side.
  const State s = spheres_along_x(thousand_along_x());
  BoxGrid grid = grid_along_x(2, {0.0});
  const ParticleWork work = particle_work(s, HistoryRows{}, HistoryRows{});
  EXPECT_EQ(work.total, 1000.0);
  double bounds[6];
  owner_bounds(grid, s, bounds);
  EXPECT_EQ(-bounds[0], 0.0005);
  EXPECT_EQ(bounds[1], 0.9995);
  const AxisSpan span = histogram_span(grid, 0, bounds);
  ASSERT_FALSE(span.empty());
  EXPECT_TRUE(histogram_span(grid, 1, bounds).empty());  // y is not cut
  // One state stands for every rank's: the histogram summed over the ranks is the whole's.
  cuts_from_histogram(grid, 0, work_histogram(grid, s, work.work, 0, span), work.total, span);
  const double cut = grid.cuts[0][0];
  EXPECT_GT(cut, 0.4995);
  EXPECT_LT(cut, 0.5005);
  EXPECT_NEAR(cut, 0.5, 0.001);
  int below = 0;
  for (double x : s.x) below += grid.owner(std::array<double, 3>{x, 0.0, 0.0}.data()) == 0;
  EXPECT_EQ(below, 500);
}

TEST(Decomposition, CutsFollowTheWorkNotTheCount) {
  // The lower half's 500 particles weigh 2, the upper half's 1: total 1500, half 750 = 375
  // particles of the lower half. The cut lies between the 375th (0.3745 m) and the 376th
  // (0.3755 m).
  const State s = spheres_along_x(thousand_along_x());
  BoxGrid grid = grid_along_x(2, {0.0});
  std::vector<double> work;
  for (double x : s.x) work.push_back(x < 0.5 ? 2.0 : 1.0);
  double bounds[6];
  owner_bounds(grid, s, bounds);
  const AxisSpan span = histogram_span(grid, 0, bounds);
  cuts_from_histogram(grid, 0, work_histogram(grid, s, work, 0, span), 1500.0, span);
  EXPECT_GT(grid.cuts[0][0], 0.3745);
  EXPECT_LT(grid.cuts[0][0], 0.3755);
  double below = 0;
  for (size_t p = 0; p < s.size(); ++p) below += s.x[p] < grid.cuts[0][0] ? work[p] : 0.0;
  EXPECT_EQ(below, 750.0);
}

TEST(Decomposition, AWorkHistogramOfAPeriodicAxisSpansThePeriod) {
  BoxGrid grid = grid_along_x(2, {0.5}, 1.0, 2.0);
  const double bounds[6] = {-2.2, 2.4, 0, 0, 0, 0};  // the particles span 2.2 to 2.4 m
  const AxisSpan span = histogram_span(grid, 0, bounds);
  EXPECT_EQ(span.lo, 2.0);
  EXPECT_EQ(span.hi, 3.0);
}

TEST(Decomposition, CutsKeepEveryBoxOneReachWide) {
  // Non-periodic, box_min 1/8 m (binary fractions: exact sums): cuts 0.5, 0.5625, 1 leave the
  // second box 1/16 m wide; its upper cut goes up to 0.625. The outer boxes reach to infinity.
  BoxGrid grid = grid_along_x(4, {0.5, 0.5625, 1.0});
  grid.box_min = 0.125;
  grid.keep_boxes_wide(0);
  EXPECT_EQ(grid.cuts[0], (std::vector<double>{0.5, 0.625, 1.0}));
  // Periodic over [0, 1] m, box_min 1/4 m: a cut at 1/8 leaves the first box too narrow (-> 1/4),
  // one at 7/8 the last (-> 3/4).
  BoxGrid low_cut = grid_along_x(2, {0.125}, 1.0);
  low_cut.box_min = 0.25;
  low_cut.keep_boxes_wide(0);
  EXPECT_EQ(low_cut.cuts[0][0], 0.25);
  BoxGrid high_cut = grid_along_x(2, {0.875}, 1.0);
  high_cut.box_min = 0.25;
  high_cut.keep_boxes_wide(0);
  EXPECT_EQ(high_cut.cuts[0][0], 0.75);
}

// ---------------------------------------------------------------------------------------------
// Owners

TEST(Decomposition, APointOnACutBelongsToTheBoxAbove) {
  const BoxGrid grid = grid_along_x(2, {0.5});
  const auto owner = [&](double x) { return grid.owner(std::array<double, 3>{x, 0.0, 0.0}.data()); };
  EXPECT_EQ(owner(0.4999), 0);
  EXPECT_EQ(owner(0.5), 1);
  EXPECT_EQ(owner(std::nextafter(0.5, 0.0)), 0);
  // The outer boxes reach to infinity.
  EXPECT_EQ(owner(-1e9), 0);
  EXPECT_EQ(owner(1e9), 1);
  const int first[3] = {0, 0, 0}, second[3] = {1, 0, 0};
  EXPECT_EQ(grid.box_low(first, 0), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(grid.box_high(first, 0), 0.5);
  EXPECT_EQ(grid.box_low(second, 0), 0.5);
  EXPECT_EQ(grid.box_high(second, 0), std::numeric_limits<double>::infinity());
}

TEST(Decomposition, OwnersAcrossAPeriod) {
  // Periodic over [0, 1] m cut at 0.5: 1.2 is 0.2 one period on (box 0), -0.3 is 0.7 (box 1),
  // 1.0 is 0.0 (box 0), -0.5 is 0.5, on the cut (box 1).
  const BoxGrid grid = grid_along_x(2, {0.5}, 1.0);
  const auto owner = [&](double x) { return grid.owner(std::array<double, 3>{x, 0.0, 0.0}.data()); };
  EXPECT_EQ(owner(1.2), 0);
  EXPECT_EQ(owner(-0.3), 1);
  EXPECT_EQ(owner(1.0), 0);
  EXPECT_EQ(owner(0.9999), 1);
  EXPECT_EQ(owner(-0.5), 1);
  const int first[3] = {0, 0, 0}, second[3] = {1, 0, 0};
  EXPECT_EQ(grid.box_low(first, 0), 0.0);
  EXPECT_EQ(grid.box_high(second, 0), 1.0);
  // A period that starts at 2 m: 3.7 is 2.7, above the cut at 2.5.
  const BoxGrid shifted = grid_along_x(2, {2.5}, 1.0, 2.0);
  EXPECT_EQ(shifted.owner(std::array<double, 3>{3.7, 0.0, 0.0}.data()), 1);
  EXPECT_EQ(shifted.owner(std::array<double, 3>{1.9, 0.0, 0.0}.data()), 1);  // 2.9
  EXPECT_EQ(shifted.owner(std::array<double, 3>{4.1, 0.0, 0.0}.data()), 0);  // 2.1
}

TEST(Decomposition, RanksNumberTheBoxesXFastest) {
  // 2 x 2 x 2 cut at 0.5 m along each axis: (0.7, 0.2, 0.9) is in box (1, 0, 1), rank
  // 1 + 2 x (0 + 2 x 1) = 5.
  BoxGrid grid = box_grid({2, 2, 2}, plain_model(), 0.01);
  for (auto& c : grid.cuts) c = {0.5};
  const double at[3] = {0.7, 0.2, 0.9};
  EXPECT_EQ(grid.owner(at), 5);
  int place[3];
  grid.place_of(5, place);
  EXPECT_EQ(place[0], 1);
  EXPECT_EQ(place[1], 0);
  EXPECT_EQ(place[2], 1);
  const int last[3] = {1, 1, 1};
  EXPECT_EQ(grid.rank_of(last), 7);
}

TEST(Decomposition, WrappingMovesAClumpWholeByItsCentre) {
  // Periodic over [0, 1] m: a free sphere at 1.25 m wraps to 0.25; a clump centred at 1.1 m with a
  // sphere 0.05 m beyond its centre moves by the centre's period, sphere to 0.15 m (not wrapped on
  // its own); both belong where their centre is.
  const BoxGrid grid = grid_along_x(2, {0.5}, 1.0);
  State s;
  s.add_sphere(1.25, 0.0, 0.0, 0.01, 1000.0, 0);
  const double q[4] = {1.0, 0.0, 0.0, 0.0}, inertia[3] = {1e-6, 1e-6, 1e-6};
  const size_t body = s.add_body(1.1, 0.0, 0.0, q, 0.01, inertia);
  const size_t member = s.add_sphere(1.15, 0.0, 0.0, 0.01, 1000.0, 0);
  s.attach(member, body, 0.05, 0.0, 0.0);
  wrap_periodic_axes(grid, s);
  EXPECT_NEAR(s.x[0], 0.25, 1e-12);
  EXPECT_NEAR(s.bodies.x[body], 0.1, 1e-12);
  EXPECT_NEAR(s.x[member], 0.15, 1e-12);
  EXPECT_EQ(owner_coordinate(s, member, 0), s.bodies.x[body]);
  EXPECT_EQ(owner_coordinate(s, 0, 0), s.x[0]);
}

TEST(Decomposition, AClumpLeavesWithItsCentre) {
  // Two boxes cut at 0.5 m, seen from rank 0: a free sphere at 0.3 stays, one at 0.7 goes to 1; a
  // clump centred at 0.45 keeps its sphere at 0.55; a clump centred at 0.6 takes its sphere at 0.48.
  const BoxGrid grid = grid_along_x(2, {0.5});
  State s;
  s.add_sphere(0.3, 0.0, 0.0, 0.01, 1000.0, 0);
  s.add_sphere(0.7, 0.0, 0.0, 0.01, 1000.0, 0);
  const double q[4] = {1.0, 0.0, 0.0, 0.0}, inertia[3] = {1e-6, 1e-6, 1e-6};
  const size_t staying = s.add_body(0.45, 0.0, 0.0, q, 0.01, inertia);
  s.attach(s.add_sphere(0.55, 0.0, 0.0, 0.01, 1000.0, 0), staying, 0.1, 0.0, 0.0);
  const size_t leaving = s.add_body(0.6, 0.0, 0.0, q, 0.01, inertia);
  s.attach(s.add_sphere(0.48, 0.0, 0.0, 0.01, 1000.0, 0), leaving, -0.12, 0.0, 0.0);
  const Departures away = departures(grid, s, 0);
  EXPECT_EQ(away.slot_to, (std::vector<int>{-1, 1, -1, 1}));
  EXPECT_EQ(away.body_to, (std::vector<int>{-1, 1}));
  // Seen from rank 1, the free sphere at 0.3 and the clump centred at 0.45 go to 0.
  const Departures back = departures(grid, s, 1);
  EXPECT_EQ(back.slot_to, (std::vector<int>{0, -1, 0, -1}));
  EXPECT_EQ(back.body_to, (std::vector<int>{0, -1}));
}

// ---------------------------------------------------------------------------------------------
// Ghosts

TEST(Decomposition, BoxOffsetsAreThirteenUpperAndThirteenLower) {
  const std::vector<BoxOffset> offsets = box_offsets();
  ASSERT_EQ(offsets.size(), 26u);
  int upper = 0;
  for (size_t k = 0; k < offsets.size(); ++k) {
    upper += offsets[k].upper();
    EXPECT_EQ(offset_index(offsets[k].d), static_cast<int>(k));
    // A box is upper to its neighbour exactly when its neighbour is lower to it.
    const BoxOffset opposite{{-offsets[k].d[0], -offsets[k].d[1], -offsets[k].d[2]}};
    EXPECT_NE(offsets[k].upper(), opposite.upper());
  }
  EXPECT_EQ(upper, 13);
  EXPECT_TRUE((BoxOffset{{0, 0, 1}}.upper()));
  EXPECT_TRUE((BoxOffset{{-1, -1, 1}}.upper()));   // z first
  EXPECT_TRUE((BoxOffset{{-1, 1, 0}}.upper()));    // then y
  EXPECT_FALSE((BoxOffset{{1, -1, 0}}.upper()));
  EXPECT_FALSE((BoxOffset{{-1, 0, 0}}.upper()));   // then x
}

TEST(Decomposition, AnInteriorBoxHasThirteenNeighboursBelowAndThirteenAbove) {
  BoxGrid grid = box_grid({3, 3, 3}, plain_model(), 0.01);
  for (auto& c : grid.cuts) c = {1.0, 2.0};
  const int centre[3] = {1, 1, 1};
  const Neighbourhood around = grid.neighbourhood(centre);
  EXPECT_EQ(around.lower.size(), 13u);
  EXPECT_EQ(around.upper.size(), 13u);
  ASSERT_EQ(around.near.size(), 26u);
  EXPECT_EQ(around.near.front(), 0);
  EXPECT_EQ(around.near.back(), 26);
  EXPECT_EQ(std::count(around.near.begin(), around.near.end(), 13), 0);  // not itself
  // The corner box of 2 x 2 x 2: 7 neighbours, all above it; the opposite corner's all below.
  const BoxGrid cube = box_grid({2, 2, 2}, plain_model(), 0.01);
  const int first[3] = {0, 0, 0}, last[3] = {1, 1, 1};
  EXPECT_EQ(cube.neighbourhood(first).upper.size(), 7u);
  EXPECT_EQ(cube.neighbourhood(first).lower.size(), 0u);
  EXPECT_EQ(cube.neighbourhood(first).near, (std::vector<int>{1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(cube.neighbourhood(last).lower.size(), 7u);
  EXPECT_EQ(cube.neighbourhood(last).upper.size(), 0u);
}

TEST(Decomposition, TwoBoxesAcrossAPeriodAreEachOthersNeighbourBelowAndAbove) {
  // Periodic over [0, 1] m in two boxes: box 0's lower neighbour across x is box 1 seen one period
  // down, so what box 0 sends it is shifted by +1 m; its upper neighbour is box 1 as it is.
  const BoxGrid grid = grid_along_x(2, {0.5}, 1.0);
  const int first[3] = {0, 0, 0}, second[3] = {1, 0, 0};
  const Neighbourhood zero = grid.neighbourhood(first);
  ASSERT_EQ(zero.lower.size(), 1u);
  ASSERT_EQ(zero.upper.size(), 1u);
  EXPECT_EQ(zero.lower[0].rank, 1);
  EXPECT_EQ(zero.lower[0].offset.d[0], -1);
  EXPECT_EQ(zero.lower[0].shift[0], 1.0);
  EXPECT_EQ(zero.upper[0].rank, 1);
  EXPECT_EQ(zero.upper[0].shift[0], 0.0);
  EXPECT_EQ(zero.near, (std::vector<int>{1}));
  const Neighbourhood one = grid.neighbourhood(second);
  ASSERT_EQ(one.upper.size(), 1u);
  ASSERT_EQ(one.lower.size(), 1u);
  EXPECT_EQ(one.upper[0].rank, 0);
  EXPECT_EQ(one.upper[0].shift[0], -1.0);
  EXPECT_EQ(one.lower[0].shift[0], 0.0);
  // Not periodic: the two boxes are one neighbour each, box 0 below box 1.
  const BoxGrid open = grid_along_x(2, {0.5});
  EXPECT_EQ(open.neighbourhood(first).lower.size(), 0u);
  EXPECT_EQ(open.neighbourhood(first).upper.size(), 1u);
}

TEST(Decomposition, AGhostGoesToTheNeighboursOfTheFacesEdgesAndCornerItIsNear) {
  // The centre box [1, 2]^3 m of a 3 x 3 x 3 grid, reach 0.1 m. A particle goes as a ghost to
  // those of its box's 13 lower neighbours whose shared face, edge or corner it lies within one
  // reach of (for each of them, this box is among its 13 upper neighbours).
  BoxGrid grid = box_grid({3, 3, 3}, plain_model(), 0.1);
  for (auto& c : grid.cuts) c = {1.0, 2.0};
  const int centre[3] = {1, 1, 1};
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = grid.box_low(centre, a), hi[a] = grid.box_high(centre, a);
  EXPECT_EQ(lo[0], 1.0);
  EXPECT_EQ(hi[2], 2.0);
  const Neighbourhood around = grid.neighbourhood(centre);
  const double reach = 0.1;
  const auto sent = [&](double x, double y, double z) {
    const double at[3] = {x, y, z};
    return receivers(around, at, lo, hi, reach);
  };
  // Near the low x face: the box across it. Near the high x face: none (the box across it is
  // above this one; it sends, this box lists the pairs).
  EXPECT_EQ(sent(1.05, 1.5, 1.5), (Offsets{{-1, 0, 0}}));
  EXPECT_EQ(sent(1.95, 1.5, 1.5), Offsets{});
  EXPECT_EQ(sent(1.5, 1.5, 1.5), Offsets{});
  // Near the edge of low x and low y: the two boxes across its faces and the one across the edge.
  EXPECT_EQ(sent(1.05, 1.05, 1.5), (Offsets{{-1, 0, 0}, {0, -1, 0}, {-1, -1, 0}}));
  // Near the edge of low x and high y: (0, 1, 0) and (-1, 1, 0) lie above (y before x).
  EXPECT_EQ(sent(1.05, 1.95, 1.5), (Offsets{{-1, 0, 0}}));
  // Near the low corner: all seven boxes around it.
  EXPECT_EQ(sent(1.05, 1.05, 1.05), (Offsets{{-1, 0, 0}, {0, -1, 0}, {-1, -1, 0}, {0, 0, -1}, {-1, 0, -1}, {0, -1, -1}, {-1, -1, -1}}));
  // Near the corner of high x, low y, low z: of its seven boxes, (1, 0, 0) lies above.
  EXPECT_EQ(sent(1.95, 1.05, 1.05), (Offsets{{0, -1, 0}, {1, -1, 0}, {0, 0, -1}, {1, 0, -1}, {0, -1, -1}, {1, -1, -1}}));
  // One reach from the face exactly is outside the layer; just inside it, in.
  EXPECT_EQ(sent(lo[0] + reach, 1.5, 1.5), Offsets{});
  EXPECT_EQ(sent(std::nextafter(lo[0] + reach, 0.0), 1.5, 1.5), (Offsets{{-1, 0, 0}}));
}

TEST(Decomposition, AParticleNearACornerIsAGhostOfTheSevenBoxesBelowIt) {
  // The same 3 x 3 x 3 grid seen from the receivers: a particle of the top corner box (2, 2, 2),
  // rank 26, 5 cm above the corner it shares with the centre box, goes to the seven boxes around
  // that corner: ranks 13 (the centre, for which box 26 is its upper neighbour (1, 1, 1)), 14,
  // 16, 17, 22, 23 and 25 (x + 3 y + 9 z).
  BoxGrid grid = box_grid({3, 3, 3}, plain_model(), 0.1);
  for (auto& c : grid.cuts) c = {1.0, 2.0};
  const double at[3] = {2.05, 2.05, 2.05};
  ASSERT_EQ(grid.owner(at), 26);
  int place[3];
  grid.place_of(26, place);
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = grid.box_low(place, a), hi[a] = grid.box_high(place, a);
  std::set<int> ranks;
  for (const NeighbourBox& n : grid.neighbourhood(place).lower)
    if (near_shared_boundary(n.offset, at, lo, hi, 0.1)) ranks.insert(n.rank);
  EXPECT_EQ(ranks, (std::set<int>{13, 14, 16, 17, 22, 23, 25}));
}

TEST(Decomposition, GhostSlotsAreOwnedSlotsInSlotOrder) {
  // Box [1, 2]^3, the neighbour across the low x face, reach 0.1 m: slots 0 and 2 lie within
  // 0.1 m of x = 1; slot 1 does not; slot 3 is a ghost itself and never sent on.
  State s;
  s.add_sphere(1.05, 1.5, 1.5, 0.01, 1000.0, 0);
  s.add_sphere(1.5, 1.5, 1.5, 0.01, 1000.0, 0);
  s.add_sphere(1.02, 1.3, 1.7, 0.01, 1000.0, 0);
  s.add_sphere(1.01, 1.5, 1.5, 0.01, 1000.0, 0);
  s.ghosts = 1;
  const double lo[3] = {1.0, 1.0, 1.0}, hi[3] = {2.0, 2.0, 2.0};
  std::vector<std::int32_t> slots = {7, 7, 7};  // replaced, not appended to
  ghost_slots(s, BoxOffset{{-1, 0, 0}}, lo, hi, 0.1, slots);
  EXPECT_EQ(slots, (std::vector<std::int32_t>{0, 2}));
}

// ---------------------------------------------------------------------------------------------
// Rebalancing

TEST(Decomposition, WorkIsOnePlusTheContacts) {
  // Ids 0, 1, 2; pairs 0-1, 0-2 and 0-99 (99 lives on another rank); particle 2 touches wall 1.
  // Work: 1 + 3 = 4, 1 + 1 = 2, 1 + 1 + 1 = 3 (the wall's index 1 is no particle: id 1 keeps 2).
  const State s = spheres_along_x({0.1, 0.2, 0.3});
  HistoryRows pairs, walls;
  const double row[1] = {0.0};
  pairs.add(0, 1, row, 1), pairs.add(0, 2, row, 1), pairs.add(0, 99, row, 1);
  walls.add(2, 1, row, 1);
  ParticleWork work = particle_work(s, pairs, walls);
  EXPECT_EQ(work.work, (std::vector<double>{4.0, 2.0, 3.0}));
  EXPECT_EQ(work.total, 9.0);
  // Balanced by time: 0.9 s shared by that work, 0.1 s a unit.
  share_time(work, 0.9);
  EXPECT_EQ(work.total, 0.9);
  EXPECT_NEAR(work.work[0], 0.4, 1e-15);
  EXPECT_NEAR(work.work[1], 0.2, 1e-15);
  EXPECT_NEAR(work.work[2], 0.3, 1e-15);
}

TEST(Decomposition, CutsMoveAfterTwentyStepsOfWaitingAboveTenPercent) {
  // Two ranks, 400 in all (mean 200), the most loaded carries 300: 50 % above the mean, and the
  // others wait half a step's worth every step. After 30 steps 15 steps' worth: not yet; after
  // 40, 20: the cuts move and the waiting starts again.
  RebalanceClock clock;
  EXPECT_FALSE(clock.due(300.0, 400.0, 2, 30, false));
  EXPECT_EQ(clock.waited_steps, 15.0);
  EXPECT_EQ(clock.checked_at_step, 30);
  EXPECT_TRUE(clock.due(300.0, 400.0, 2, 40, false));
  EXPECT_EQ(clock.waited_steps, 0.0);
  EXPECT_FALSE(clock.due(300.0, 400.0, 2, 41, false));
  EXPECT_EQ(clock.waited_steps, 0.5);
}

TEST(Decomposition, CutsStayAtTenPercentOrLessHoweverLongTheWait) {
  // 215 against a mean of 200 (7.5 % above): 1000 steps add 75 steps' worth of waiting, yet the
  // cuts stay. At 220 (10 % exactly) they stay too. At 230 (15 %) the waiting so far moves them.
  RebalanceClock clock;
  EXPECT_FALSE(clock.due(215.0, 400.0, 2, 1000, false));
  EXPECT_NEAR(clock.waited_steps, 75.0, 1e-9);
  EXPECT_FALSE(clock.due(220.0, 400.0, 2, 1001, false));
  EXPECT_TRUE(clock.due(230.0, 400.0, 2, 1002, false));
}

TEST(Decomposition, CutsStayWithFewerParticlesThanRanksOrNoMeasuredTime) {
  // Balanced by work, less than one particle a rank: nothing to balance, and the waiting is not
  // counted. Balanced by time, seconds count however few: 0.4 s against a mean of 0.25 s is 60 %
  // above it, 40 steps of it 24 steps' worth.
  RebalanceClock clock;
  EXPECT_FALSE(clock.due(1.5, 1.5, 2, 100, false));
  EXPECT_EQ(clock.checked_at_step, 0);
  EXPECT_EQ(clock.waited_steps, 0.0);
  EXPECT_FALSE(clock.due(0.0, 0.0, 2, 100, true));
  EXPECT_EQ(clock.checked_at_step, 0);
  RebalanceClock timed;
  EXPECT_TRUE(timed.due(0.4, 0.5, 2, 40, true));
}

}  // namespace
}  // namespace dem
