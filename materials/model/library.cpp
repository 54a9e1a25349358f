#include "model/library.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "case/spec.h"

namespace dem::materials {

std::string library_folder() { return DEMDESIGN_MATERIALS_DIR; }

std::vector<std::string> library_folders() {
  std::vector<std::string> out;
  if (const char* env = std::getenv("DEMDESIGN_MATERIALS"); env && *env) out.emplace_back(env);
  out.push_back(library_folder());
  return out;
}

LibraryLookup library_lookup() {
  return [](const std::string& file, const std::string&, std::string& searched) {
    for (const std::string& folder : library_folders()) {
      const std::filesystem::path candidate = std::filesystem::path(folder) / (file + ".yaml");
      searched += "\n  " + candidate.lexically_normal().string();
      if (std::filesystem::is_regular_file(candidate)) return candidate;
    }
    return std::filesystem::path();
  };
}

std::vector<LibraryEntry> list_library(const std::string& folder) {
  std::vector<LibraryEntry> out;
  const std::filesystem::path dir = folder.empty() ? library_folder() : folder;
  if (!std::filesystem::is_directory(dir)) return out;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    LibraryEntry e{entry.path().stem().string(), "", entry.path().string()};
    try {
      const YAML::Node root = YAML::LoadFile(e.path);
      if (root["description"]) e.description = root["description"].as<std::string>();
    } catch (const YAML::Exception& error) {
      e.description = std::string("unreadable: ") + error.what();
    }
    out.push_back(std::move(e));
  }
  std::sort(out.begin(), out.end(), [](const LibraryEntry& a, const LibraryEntry& b) { return a.name < b.name; });
  return out;
}

}  // namespace dem::materials
