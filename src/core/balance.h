// How the threads share the spheres, step after step. The slots are cut into blocks (every pair
// (i, j) has j in i's block or the next: Workspace::block, forces.cpp). Each thread takes a
// contiguous run of blocks holding about its share of the measured work, and keeps it for every
// pass over the spheres of a step (the kick-drift, the contacts, gravity and the closing kick):
// a thread then finds its spheres in its own cache, and no thread idles while another finishes.
//
// The work of a block is the time its passes took, averaged over the steps (half the last step,
// half the estimate before); after the blocks change it is estimated from the pairs listed
// until it has been measured once. Who takes which block changes the speed only: the sums are
// made in an order fixed by the data (forces.cpp), so the results are bitwise the same.
// Rejected: OpenMP's dynamic schedule over the blocks (what the contact pass did first): the
// blocks of one half ran on whichever thread was free, so their spheres moved between the
// cores' caches every step, and the two halves needed a barrier each. Measured against it,
// blocks kept by their thread ran faster on the settle and the dense bed
// (bench/results/design_measurements.csv).
#pragma once

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <utility>

#include "core/workspace.h"

namespace dem {

/// Before a contact pass over n owned slots: the step's measured times folded into the blocks'
/// work, the running sum of that work for thread_blocks, a new pass number for block_done.
void share_blocks(Workspace& work, long n);

/// Thread t of nt: blocks [lo, hi), a contiguous run holding about 1/nt of the work. All
/// blocks to thread 0 of 1; an even split when the blocks are not those of n slots (the state
/// changed since share_blocks).
std::pair<long, long> thread_blocks(const Workspace& work, long n, int t, int nt);

/// Adds the time since `start` to block b's work of this step.
inline void add_block_time(Workspace& work, long b, std::chrono::steady_clock::time_point start) {
  work.block_time[b] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Calls f(begin, end) for each block of this thread's run (slots [begin, end), ascending) and
/// counts its time. Called by every thread of a parallel region over the n owned slots.
template <typename F>
void for_own_blocks(Workspace& work, long n, F&& f) {
  const auto [lo, hi] = thread_blocks(work, n, omp_get_thread_num(), omp_get_num_threads());
  const bool timed = static_cast<long>(work.block_time.size()) >= hi;
  for (long b = lo; b < hi; ++b) {
    const auto start = std::chrono::steady_clock::now();
    f(b * work.block, std::min(n, (b + 1) * work.block));
    if (timed) add_block_time(work, b, start);
  }
}

}  // namespace dem
