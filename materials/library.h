// The material library: the YAML files beside this header (gravel.yaml, glass_beads.yaml, ...)
// and the C++ that calibrates them against laboratory measurements (virtual tests, comparison,
// calibration, diagnosis). A case uses a library material with
//   materials: {ore: {library: gravel}}
// (src/spec.cpp resolves it); `demdesign materials` lists what is there.
#pragma once

#include <string>
#include <vector>

namespace dem::materials {

struct LibraryEntry {
  std::string name;         ///< file stem, the name a case uses
  std::string description;  ///< the file's `description`
  std::string path;
};

/// The materials in `folder` (default: the library shipped with the source tree), sorted by
/// name. Files that cannot be read are listed with the error as description.
std::vector<LibraryEntry> list_library(const std::string& folder = "");

/// The folder of the shipped library.
std::string library_folder();

}  // namespace dem::materials
