// Checkpoints: the whole State (particles, bodies, walls, inlets, outlets, contact lists with
// their history, and the positions the lists were built at) with the model's hash, in one
// binary file written atomically. A run restarted from it continues bitwise as the
// uninterrupted run would have.
#pragma once

#include <string>

#include "core/model.h"
#include "core/state.h"

namespace dem {

/// Writes `path` through a temporary file and a rename.
void save_checkpoint(const std::string& path, const Model& model, const State& state);
/// Reads a checkpoint; throws std::runtime_error naming the file when it is unreadable, from
/// another version, or from a different model (its hash differs).
State load_checkpoint(const std::string& path, const Model& model);

}  // namespace dem
