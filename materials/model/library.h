// The material library: the YAML files beside this header (gravel.yaml, glass_beads.yaml, ...)
// and the C++ that calibrates them against laboratory measurements (virtual tests, comparison,
// calibration, diagnosis). A case uses a library material with
//   materials: {ore: {library: gravel}}
// (the case reader, src/case/spec_materials.cpp, reads the file; where it is found is said here:
// library_lookup). `demdesign materials` lists what is there.
#pragma once

#include <string>
#include <vector>

#include "case/spec.h"

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

/// Where a case finds its library materials beyond its own folders: library_folders(), read when
/// a case asks. A program passes it where it parses a case (dem::parse_case_file(path,
/// library_lookup()); why it is passed and not set once: dem::LibraryLookup, case/spec.h);
/// read_material_model passes it itself.
LibraryLookup library_lookup();

}  // namespace dem::materials
