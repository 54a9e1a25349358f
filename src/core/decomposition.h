// Spatial domain decomposition, its geometry and its rules: how the ranks of a split run cut the
// domain into a grid of boxes, which box a particle belongs to, which particles a box copies to
// its neighbours as ghosts, and when the cuts move. Functions of numbers, models and states that
// send nothing: app/mpi/mpi_domain.cpp carries particles, ghosts, loads and sums between the
// ranks around them, and src/core/domain.h is what a step sees of the ranks. Kept apart from the
// messages so that a grid, a cut, an owner or a ghost set is checked with numbers in one process
// (tests/test_decomposition.cpp); checked only through split runs, a wrong ghost shows as a
// statistical difference between flows, if at all.
//
// The grid: of the factorisations nx x ny x nz of the rank count, the one whose boxes share the
// least face area with their neighbours, over the extent the particles and the domain box span
// (a periodic axis counts with its period, the axis of gravity at half its extent: particles
// travel along it), with every box at least one ghost reach wide along each axis it is cut across.
// The outer boxes of a non-periodic axis reach to infinity; along a periodic axis the last box's
// upper neighbour is the first, seen one period on. Rank r is the box (r mod nx, r / nx mod ny,
// r / (nx ny)).
//
// The cuts along each axis sit at quantiles of the work (a particle weighs one plus its contacts;
// or, balanced by time, each rank's measured computing time since the last rebuild, shared among
// its particles by that weight), recomputed at a rebuild when the most loaded rank carries more
// than 10 % above the mean and the ranks have, since the last rebalance, waited for the most
// loaded one 20 steps' worth of the mean rank's work. Rejected: the imbalance alone, with which a
// flow that keeps moving (an inlet feeding one rank) moved the cuts at nearly every rebuild.
// Time-balanced cuts depend on the machine's timing, so such runs are not reproducible bit for
// bit; the default is reproducible. A point on a cut belongs to the box above it.
//
// Ghosts: of its up to 26 neighbours, a box receives the particles of the 13 that lie above it
// (z first, then y, then x), within one reach of the faces, edges or corner they share, and lists
// the pairs with them; the forces on those ghosts go back to their owners. A pair across ranks is
// thus listed once. Seen from the sender, a particle goes to those of its box's 13 lower
// neighbours whose shared faces, edges or corner it lies within one reach of.
//
// Clumps belong to the box of their centre and move with all their spheres; the ghost layer and
// the narrowest box are deeper by how far a clump's spheres stick out.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem {

/// Rebalance when the most loaded rank carries more than this times the mean work ...
inline constexpr double kRebalanceImbalance = 1.10;
/// ... and when the ranks have waited for the most loaded, since the last rebalance, at least this
/// many steps' worth of the mean rank's work (the sum over the steps of most / mean - 1): what
/// moving the cuts costs (histograms, all-to-all migration, new ghosts), in steps.
inline constexpr double kRebalanceAfterSteps = 20;
/// Bins of the work histogram along a cut axis, at whose quantiles the new cuts sit: a cut lands
/// within 1/4096 of the axis's span of its quantile, interpolated inside its bin.
inline constexpr int kWorkHistogramBins = 4096;

// ---------------------------------------------------------------------------------------------
// The grid of boxes

/// How deep the ghost layer is and how narrow a box may be, for the particles a case starts with
/// and the particles its inlets can create.
struct GhostReach {
  double sticking_out = 0;  // [m] how far a clump's sphere centre lies from the clump's centre
  double reach = 0;         // [m] ghost layer depth: a pair's largest listing distance + sticking_out
  double box_min = 0;       // [m] narrowest box along a cut axis: reach + sticking_out
};
GhostReach ghost_reach(const Model& model, const State& initial);

/// How far the particles and the domain box spread along each axis, what the grid is chosen on.
struct GridSpan {
  double extent[3] = {0, 0, 0};               // [m] the particles' and the domain box's; a periodic axis: its period
  double score[3] = {0, 0, 0};                // [m] extent, the axis of gravity at half
  bool periodic[3] = {false, false, false};   ///< the model's periodic axes
};
GridSpan grid_span(const Model& model, const State& initial);

/// Whether every box of the grid `n` is at least `narrowest` [m] wide along each cut axis of
/// `extent` [m] (`periodic`: every box; otherwise the outer boxes reach to infinity).
bool grid_fits(const std::array<int, 3>& n, const double extent[3], const bool periodic[3], double narrowest);

/// A rank grid for `ranks` over boxes of `extent` [m] (per axis, a score: the axis of gravity
/// counts half, GridSpan::score), each cut axis at least `narrowest` [m] a box (`periodic`: every
/// box; otherwise the outer boxes reach to infinity): the factorisation whose busiest box shares
/// the least face area with its neighbours (an interior box has two faces across a cut axis, an
/// outer box of two one, a periodic axis always two), and of equal ones the one with fewer cut
/// axes (fewer neighbours, fewer messages); {0, 0, 0} when none fits.
std::array<int, 3> choose_grid(int ranks, const double extent[3], const bool periodic[3], double narrowest);

/// One of the 26 offsets from a box to its neighbours in the grid (-1, 0 or 1 along each axis).
struct BoxOffset {
  int d[3];
  /// Lexicographically positive (z first): a box receives that neighbour's particles as ghosts
  /// and lists the pairs across their common faces, edges and corners; the neighbour receives
  /// none of the box's. Every pair across ranks is thus listed once.
  bool upper() const { return d[2] > 0 || (d[2] == 0 && (d[1] > 0 || (d[1] == 0 && d[0] > 0))); }
};
/// The 26 offsets in a fixed order, x fastest, z slowest (the messages' tags number them).
std::vector<BoxOffset> box_offsets();
/// Where the offset `d` stands in box_offsets().
int offset_index(const int d[3]);

/// A box next to another: where it lies, its rank, and the shift [m] of what is sent to it (one
/// period where the grid wraps: what a box sends across the period is seen one period on).
struct NeighbourBox {
  BoxOffset offset;
  int rank = -1;
  double shift[3] = {0, 0, 0};  // [m]
};
/// A box's neighbours, each in the order of box_offsets(): two boxes across a period are each
/// other's neighbour twice, below and above, with other shifts.
struct Neighbourhood {
  std::vector<NeighbourBox> lower;  ///< get this box's particles as ghosts, return their loads
  std::vector<NeighbourBox> upper;  ///< send this box theirs
  std::vector<int> near;            ///< their ranks, each once, not this box's own, ascending
};

/// The grid of boxes and the cuts between them; a box is named by its place `at` (0 .. dims - 1
/// along each axis) or its rank.
struct BoxGrid {
  int dims[3] = {1, 1, 1};
  bool periodic[3] = {false, false, false};  ///< periodic and cut by the grid
  double period[3] = {0, 0, 0};              // [m] the model's period along each axis (0: none)
  double low[3] = {0, 0, 0};                 // [m] the domain's lower corner, where a period starts
  double box_min = 0;                        // [m] narrowest box along a cut axis (GhostReach)
  std::vector<double> cuts[3];               // [m] between box k and k + 1 along each axis (dims - 1)

  int rank_of(const int at[3]) const { return at[0] + dims[0] * (at[1] + dims[1] * at[2]); }
  /// The place of the box of `rank`.
  void place_of(int rank, int at[3]) const;
  /// A coordinate along axis a back into the period where the grid cuts a periodic axis.
  double wrapped(double c, int a) const;
  /// The box along axis a a coordinate falls in: how many cuts lie at or below it.
  int slot_along(double c, int a) const;
  /// The rank of the box a point [m] falls in.
  int owner(const double at[3]) const;
  /// The faces [m] of the box at `at` along axis a (infinite: an outer box of a non-periodic axis).
  double box_low(const int at[3], int a) const;
  double box_high(const int at[3], int a) const;
  /// The boxes next to the one at `at`: those that exist (an axis not cut has none; a
  /// non-periodic axis none beyond its outer boxes).
  Neighbourhood neighbourhood(const int at[3]) const;
  /// Interior boxes along axis a (all boxes of a periodic axis) at least box_min wide: the cuts
  /// pushed up from the first, then down from the last.
  void keep_boxes_wide(int a);
};

/// The grid `dims` over the model's domain and periods, without cuts yet.
BoxGrid box_grid(const std::array<int, 3>& dims, const Model& model, double box_min);
/// The model the ranks step: the periodic axes the grid cuts made non-periodic (the ranks carry
/// the period across their faces).
void clear_cut_periods(const BoxGrid& grid, Model& local);

// ---------------------------------------------------------------------------------------------
// Cuts and owners

/// Cuts between `boxes` boxes at quantiles of the particle count: the coordinate of particle
/// size * k / boxes of the `sorted` coordinates; evenly over [lo, hi] [m] when the boxes
/// outnumber the particles.
std::vector<double> quantile_cuts(const std::vector<double>& sorted, int boxes, double lo, double hi);
/// The first cuts along every axis, from a state the same on every rank (the initial particles):
/// at quantiles of the particle count over the period, the domain box or the particles' span,
/// each box then kept one box_min wide.
void first_cuts(BoxGrid& grid, const Model& model, const State& initial);

/// Where slot p belongs along axis a [m]: its own centre, or its clump's.
double owner_coordinate(const State& s, std::size_t p, int a);
/// Free spheres and clump centres back into the period along every periodic axis the grid cuts
/// (a clump's spheres move with its centre).
void wrap_periodic_axes(const BoxGrid& grid, State& s);
/// Where the particles of the box of `rank` go at a migration: the rank of the box their centre
/// lies in (a clump's spheres the box of its centre, the clump moving whole), -1 where they stay.
struct Departures {
  std::vector<int> body_to;  ///< (bodies)
  std::vector<int> slot_to;  ///< (n)
};
Departures departures(const BoxGrid& grid, const State& s, int rank);

// ---------------------------------------------------------------------------------------------
// Ghosts

/// Whether a point [m] of the box [lo, hi] lies within `reach` [m] of the faces, edges or corner
/// the box shares with its neighbour at `offset`: along each axis the offset moves, within reach
/// of that side.
bool near_shared_boundary(const BoxOffset& offset, const double at[3], const double lo[3], const double hi[3], double reach);
/// The owned slots of `s` that the box [lo, hi] sends as ghosts to its neighbour at `offset`, in
/// slot order (the order of the message), into `slots`.
void ghost_slots(const State& s, const BoxOffset& offset, const double lo[3], const double hi[3], double reach, std::vector<std::int32_t>& slots);

// ---------------------------------------------------------------------------------------------
// Rebalancing

/// A rank's work, per slot and summed in slot order: one plus the particle's contacts, or measured
/// time (share_time).
struct ParticleWork {
  std::vector<double> work;  ///< (n) [-], or [s] after share_time
  double total = 0;          ///< the sum of work
};
/// One plus the contacts with a history (pairs count for both partners, wall rows for their
/// particle): in a dense bed the contacts, not the particles, cost the time.
ParticleWork particle_work(const State& s, const HistoryRows& pairs, const HistoryRows& walls);
/// The rank's `computed` seconds (its wall time less its time in messages and packing) shared
/// among its particles by their work: what a pair across a face, a mesh contact or a slower core
/// costs is then measured, not modelled.
void share_time(ParticleWork& work, double computed);

/// Per axis the span of the owner coordinates of `s` (wrapped), as a maximum over the ranks
/// combines them: -lowest and highest, axis after axis (-infinity twice without particles).
void owner_bounds(const BoxGrid& grid, const State& s, double bounds[6]);
/// The span [m] of a work histogram along axis a.
struct AxisSpan {
  double lo = 0, hi = 0;
  bool empty() const { return !(hi > lo); }
};
/// Along a cut axis, the period or the particles' span over every rank (`bounds`: owner_bounds'
/// maximum over the ranks); empty along an axis the grid does not cut.
AxisSpan histogram_span(const BoxGrid& grid, int a, const double bounds[6]);
/// This rank's work along axis a in kWorkHistogramBins bins over `span` (what lies beyond it in
/// the outer bins).
std::vector<double> work_histogram(const BoxGrid& grid, const State& s, const std::vector<double>& work, int a, AxisSpan span);
/// New cuts along axis a at the quantiles k / dims of `total` work in `histogram` (the sum over
/// the ranks), interpolated within a bin; then keep_boxes_wide.
void cuts_from_histogram(BoxGrid& grid, int a, const std::vector<double>& histogram, double total, AxisSpan span);

/// When the cuts move: the waiting for the most loaded rank since the last rebalance, counted in
/// steps of the mean rank's work. From reduced values and step counts alone, so every rank
/// decides alike, and reproducibly when balanced by work.
struct RebalanceClock {
  std::int64_t checked_at_step = 0;  ///< the step count at the last check
  double waited_steps = 0;           ///< steps' worth of waiting for the most loaded rank since the last rebalance

  /// At a rebuild after `steps` steps: whether the cuts move, given the most loaded rank's work
  /// `most` and the ranks' `total` over `ranks` ranks (`measured_time`: seconds; otherwise
  /// particles and contacts, and fewer than one a rank leave the cuts alone). Adds the waiting
  /// since the last check, and clears it when the cuts move.
  bool due(double most, double total, int ranks, std::int64_t steps, bool measured_time);
};

}  // namespace dem
