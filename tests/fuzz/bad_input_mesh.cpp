#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "bad_input.h"
#include "mesh_health.h"
#include "triangle_mesh.h"

namespace dem::fuzz {

std::string extension_of(std::uint8_t selector) {
  static const char* const kExtensions[] = {".stl", ".obj", ".ply", ".off"};
  return kExtensions[selector % 4];
}

std::string import_mesh_bytes(const std::string& bytes, const std::string& extension) {
  static const std::filesystem::path dir = [] {
    const auto d = std::filesystem::temp_directory_path() / ("demdesign_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const std::filesystem::path file = dir / ("input" + extension);
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  std::string result;
  try {
    geometry::TriangleMesh mesh = geometry::import_mesh(file.string());
    const geometry::MeshReport report = geometry::check_and_repair(mesh, 0.01);
    if (!report.simulable()) result = report.text();
  } catch (const geometry::MeshError& e) {
    result = e.what();
  }
  std::filesystem::remove(file);
  return result;
}

}  // namespace dem::fuzz
