// The readers a user's files go through, as one call each, for the fuzzers (tests/fuzz/fuzz_*.cpp)
// and the bad-input regression tests (tests/test_bad_input.cpp). Each returns what the user
// would get: "" when the input was accepted, else the error message (CaseError or MeshError).
// Any other exception escapes, and a crash is a crash: both are findings.
#pragma once

#include <cstdint>
#include <string>

namespace dem::fuzz {

/// parse_case_text, expand_equipment, compile (inline meshes; mesh files are refused), and the
/// initial particle placement when the case holds at most `place_limit` particles.
std::string read_case_text(const std::string& text, std::int64_t place_limit = 2000);

/// dem::materials::parse_measurements, then every set-up checked against a plain 6 mm bead
/// (check_experiments: what `compare` does before any simulation).
std::string read_measurement_text(const std::string& text);

/// Writes `bytes` to a private temporary file named input`extension`, imports it
/// (geometry::import_mesh) and checks and repairs it (check_and_repair, particle diameter 10 mm).
/// Returns "" for a simulable mesh, else the MeshError or the fatal issues of the report.
std::string import_mesh_bytes(const std::string& bytes, const std::string& extension);

/// ".stl", ".obj", ".ply" or ".off" from a selector byte (the mesh fuzzer's first byte).
std::string extension_of(std::uint8_t selector);

}  // namespace dem::fuzz
