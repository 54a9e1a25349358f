// The cell grid the contact lists are built on (neighbors.cpp): cells at least one pair reach
// wide, numbered so that sorted slots keep their neighbours close, and the counting sort of the
// slots by cell.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/model.h"
#include "core/state.h"

namespace dem {

/// Cells along each axis; periodic axes span exactly one period, others the particles' extent.
/// Cells are numbered with the non-periodic axis of most cells varying slowest (`order`: minor,
/// middle, major), so that after the sort a particle's neighbours lie within a short run of slots (the
/// block size of the force evaluation, see forces.cpp) even in long, flat equipment.
struct Grid {
  double origin[3];
  double cell[3];
  int dims[3];
  bool wrap[3];
  double period[3];
  int order[3] = {0, 1, 2};
  int axis_index(int a, double v) const {
    if (wrap[a]) v -= period[a] * std::floor((v - origin[a]) / period[a]);
    return std::clamp(static_cast<int>((v - origin[a]) / cell[a]), 0, dims[a] - 1);
  }
  int encode(const int at[3]) const {
    return (at[order[2]] * dims[order[1]] + at[order[1]]) * dims[order[0]] + at[order[0]];
  }
  void decode(int c, int at[3]) const {
    at[order[0]] = c % dims[order[0]];
    at[order[1]] = (c / dims[order[0]]) % dims[order[1]];
    at[order[2]] = c / (dims[order[0]] * dims[order[1]]);
  }
  int index(double x, double y, double z) const {
    const int at[3] = {axis_index(0, x), axis_index(1, y), axis_index(2, z)};
    return encode(at);
  }
};

/// The grid over the spheres (those with keep[p] != 0 when keep is given) with cells at least
/// `cell` [m] wide, and at most about four per sphere or 2^19 (why: cell_grid.cpp).
Grid make_grid(const Model& model, const State& s, double cell, const std::uint8_t* keep = nullptr);

/// Lists the slots p in [0, n) with cell_of[p] >= 0 by cell, in slot order within a cell (a
/// counting sort): `out` gets the slots, cell_start[c] is where cell c's slots begin (n_cells + 2
/// entries, the last unused). Each cell's count is kept one place further up than its start,
/// so the scatter, which advances cell_start[c + 1] as cell c's cursor, leaves every start in
/// place: no pass over the cells afterwards to shift them back. The passes over the cells are
/// shared by the threads when there are many (in a thin stream through a large box the cells,
/// not the spheres, made most of the sort's time: bench/results/design_measurements.csv).
void sort_by_cell(const std::vector<std::int32_t>& cell_of, size_t n, int n_cells, std::vector<std::int32_t>& cell_start,
                  std::vector<std::int32_t>& out);

}  // namespace dem
