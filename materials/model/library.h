// The material library: the YAML files beside this header (gravel.yaml, glass_beads.yaml, ...)
// and the C++ that calibrates them against laboratory measurements (virtual tests, comparison,
// calibration, diagnosis). A case uses a library material with
//   materials: {ore: {library: gravel}}
// (the case reader, src/case/spec_materials.cpp, reads the file; where it is found is said here:
// use_material_library). `demdesign materials` lists what is there.
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

/// The folders a case's `library:` name is looked up in after the case's own folders:
/// $DEMDESIGN_MATERIALS (when set), then the shipped library.
std::vector<std::string> library_folders();

/// Makes the case reader find library materials in library_folders() (dem::set_library_lookup).
/// Programs that read cases call it once at start; read_material_model calls it itself.
void use_material_library();

}  // namespace dem::materials
