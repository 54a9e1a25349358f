// Checkpoints: the whole State (particles, bodies, walls, inlets, outlets, contact lists with
// their history, and the positions the lists were built at) with the model's hash and the id of
// the run that wrote it (run_folder.h), in one binary file written atomically. A run restarted from it continues bitwise as the
// uninterrupted run would have.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/state.h"

namespace dem {

/// Writes `path` through a temporary file and a rename; `run_id` names the run (0: none).
void save_checkpoint(const std::string& path, const Model& model, const State& state, std::uint64_t run_id = 0);
/// Reads a checkpoint; throws std::runtime_error naming the file when it is unreadable, from
/// another version, or from a different model (its hash differs). `run_id` (when given) gets the
/// id of the run that wrote it, 0 for a checkpoint of a version before run ids.
State load_checkpoint(const std::string& path, const Model& model, std::uint64_t* run_id = nullptr);

// Under domain decomposition (core/domain.h) no rank gathers the state for a checkpoint: each
// writes its share (pack_share) to DIR/checkpoint.ranks/step-S.rank-K-of-N.bin, and when every
// share is on disk the root writes what the ranks hold alike (shared_part) to
// DIR/checkpoint.ranks.bin, whose step names the shares that belong to it. Each file goes through
// a temporary file and a rename, so a kill at any moment leaves one complete checkpoint.

/// Writes this rank's share of the state at `step`.
void save_checkpoint_share(const std::string& directory, const Model& model, std::int64_t step, int rank, int ranks,
                           const std::vector<double>& share);
/// On the root, once every rank's share of `like.step` is written: writes checkpoint.ranks.bin and
/// removes the shares of other steps and a whole checkpoint.bin of an earlier run.
void commit_checkpoint_shares(const std::string& directory, const Model& model, const State& like, std::uint64_t run_id = 0);
/// Writes the whole state to DIR/checkpoint.bin and removes the per-rank checkpoint of an earlier run.
void save_whole_checkpoint(const std::string& directory, const Model& model, const State& state, std::uint64_t run_id = 0);

/// The state to resume from in DIR: checkpoint.bin, or the shares named by checkpoint.ranks.bin
/// merged into one state (merge_shares), whichever holds the later step; the rank count may
/// differ from the one that wrote them. `from` (when given) says which was read, `run_id` the id
/// of the run that wrote it. Throws std::runtime_error naming the file when there is none, or one
/// is unreadable or incomplete.
State load_resumable(const std::string& directory, const Model& model, std::string* from = nullptr, std::uint64_t* run_id = nullptr);

}  // namespace dem
