#include "core/balance.h"

namespace dem {

namespace {

/// Work of slots [first, last) estimated from the list: pairs and wall contacts, and a quarter
/// of a pair per sphere (seconds are measured from the first step on).
double listed_work(const Workspace& work, long first, long last) {
  return (work.pair_begin[last] - work.pair_begin[first]) + (work.wall_begin[last] - work.wall_begin[first]) +
         0.25 * static_cast<double>(last - first);
}

long block_count(const Workspace& work, long n) { return (n + work.block - 1) / work.block; }

}  // namespace

void share_blocks(Workspace& work, long n) {
  const long blocks = block_count(work, n);
  const auto size = static_cast<size_t>(blocks);
  if (work.block_work.size() != size || work.block_time.size() != size) {
    work.block_work.resize(size), work.block_time.assign(size, 0.0);
    for (long b = 0; b < blocks; ++b) work.block_work[b] = listed_work(work, b * work.block, std::min(n, (b + 1) * work.block));
    work.block_timed = false;
  } else {
    // The passes of the last step, kick-drift to closing kick, measured block by block.
    for (long b = 0; b < blocks; ++b)
      work.block_work[b] = work.block_timed ? 0.5 * (work.block_work[b] + work.block_time[b]) : work.block_time[b];
    std::fill(work.block_time.begin(), work.block_time.end(), 0.0);
    work.block_timed = true;
  }
  if (work.block_done.size() != size || ++work.pass_epoch == 0) work.block_done.assign(size, 0), work.pass_epoch = 1;
  work.block_prefix.resize(size + 1);
  work.block_prefix[0] = 0.0;
  for (long b = 0; b < blocks; ++b) work.block_prefix[b + 1] = work.block_prefix[b] + work.block_work[b];
}

std::pair<long, long> thread_blocks(const Workspace& work, long n, int t, int nt) {
  const long blocks = block_count(work, n);
  const std::vector<double>& prefix = work.block_prefix;
  const bool measured = static_cast<long>(prefix.size()) == blocks + 1 && prefix.back() > 0.0;
  const auto boundary = [&](int u) {
    if (u <= 0) return 0L;
    if (u >= nt) return blocks;
    if (!measured) return blocks * u / nt;
    const double target = prefix.back() * u / nt;
    const long b = std::lower_bound(prefix.begin(), prefix.end(), target) - prefix.begin();
    return b > 0 && target - prefix[b - 1] < prefix[b] - target ? b - 1 : b;
  };
  return {boundary(t), boundary(t + 1)};
}

}  // namespace dem
