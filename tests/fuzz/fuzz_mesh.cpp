// libFuzzer target: the mesh import path (assimp import, then the CGAL health check and repair).
// The first byte picks the extension (STL, OBJ, PLY, OFF); the rest is the file's content.
#include <cstddef>
#include <cstdint>
#include <string>

#include "bad_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1 || size > 64 * 1024) return 0;
  dem::fuzz::import_mesh_bytes(std::string(reinterpret_cast<const char*>(data + 1), size - 1),
                               dem::fuzz::extension_of(data[0]));
  return 0;
}
