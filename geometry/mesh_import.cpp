// Mesh import with assimp (https://assimp.org, Debian libassimp 5.2): one triangle soup in metres
// from any mesh file. assimp is used only here, so no other file of the project sees its headers.
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <utility>

#include "triangle_mesh.h"

namespace dem::geometry {
namespace {

using Matrix3 = std::array<std::array<double, 3>, 3>;

/// An affine map p -> linear p + offset, in double precision.
struct Affine {
  Matrix3 linear{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  std::array<double, 3> offset{0, 0, 0};

  std::array<double, 3> apply(const std::array<double, 3>& p) const {
    std::array<double, 3> out = offset;
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) out[row] += linear[row][col] * p[col];
    return out;
  }
  double determinant() const {
    const Matrix3& m = linear;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  }
};

/// outer(inner(p)): the composition of two affine maps.
Affine compose(const Affine& outer, const Affine& inner) {
  Affine out;
  for (int row = 0; row < 3; ++row) {
    out.offset[row] = outer.offset[row];
    for (int col = 0; col < 3; ++col) {
      out.linear[row][col] = 0;
      for (int k = 0; k < 3; ++k) out.linear[row][col] += outer.linear[row][k] * inner.linear[k][col];
      out.offset[row] += outer.linear[row][col] * inner.offset[col];
    }
  }
  return out;
}

/// assimp's row-major 4x4 node matrix (translation in the fourth column) as an Affine.
Affine from_assimp(const aiMatrix4x4& m) {
  Affine out;
  const ai_real* rows[3] = {&m.a1, &m.b1, &m.c1};
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) out.linear[row][col] = rows[row][col];
    out.offset[row] = rows[row][3];
  }
  return out;
}

/// The user's placement: translate + Rz Ry Rx (scale * unit_scale * p).
Affine from_options(const ImportOptions& options) {
  const auto rotation = [](int axis, double degrees) {
    const double angle = degrees * std::numbers::pi / 180.0;  // [rad]
    const double c = std::cos(angle), s = std::sin(angle);
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;  // the plane the rotation turns
    Affine r;
    r.linear[a][a] = c;
    r.linear[a][b] = -s;
    r.linear[b][a] = s;
    r.linear[b][b] = c;
    return r;
  };
  Affine scaling;
  for (int axis = 0; axis < 3; ++axis) scaling.linear[axis][axis] = options.unit_scale * options.scale[axis];
  Affine placed =
      compose(rotation(2, options.rotate_deg[2]),
              compose(rotation(1, options.rotate_deg[1]), compose(rotation(0, options.rotate_deg[0]), scaling)));
  placed.offset = options.translate;
  return placed;
}

std::string lower_extension(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

bool is_brep_cad(const std::string& path) {
  const std::string extension = lower_extension(path);
  return extension == ".step" || extension == ".stp" || extension == ".iges" || extension == ".igs";
}

constexpr const char* kExportAdvice =
    "export the surface from the CAD program as a triangle mesh (STL, OBJ, PLY, 3MF or glTF)";

/// Joins vertices at bitwise identical positions (after -0 is made +0), keeping first-seen order.
class VertexWelder {
 public:
  explicit VertexWelder(std::vector<std::array<double, 3>>& vertices) : vertices_(vertices) {}
  std::int32_t index_of(std::array<double, 3> p) {
    for (double& x : p)
      if (x == 0.0) x = 0.0;  // -0.0 == 0.0: one key for both
    const auto [it, inserted] = index_.try_emplace(p, static_cast<std::int32_t>(vertices_.size()));
    if (inserted) vertices_.push_back(p);
    return it->second;
  }

 private:
  struct Hash {
    std::size_t operator()(const std::array<double, 3>& p) const {
      std::size_t h = 1469598103934665603ull;
      for (double x : p) {
        std::uint64_t bits;
        std::memcpy(&bits, &x, sizeof bits);
        h = (h ^ bits) * 1099511628211ull;
        h ^= h >> 29;
      }
      return h;
    }
  };
  std::vector<std::array<double, 3>>& vertices_;
  std::unordered_map<std::array<double, 3>, std::int32_t, Hash> index_;
};

/// Appends the triangles of `mesh`, placed by `placement`, to `out`; returns how many faces were
/// points or lines (dropped). A mirroring placement reverses the winding to keep it outward.
/// Triangles (in file order) with a non-finite corner: how many, and up to 10 examples.
struct NonFinite {
  std::vector<std::size_t> examples;
  std::size_t count = 0;
};

std::size_t append_mesh(const aiMesh& mesh, const Affine& placement, VertexWelder& welder, TriangleMesh& out, NonFinite& bad) {
  std::size_t dropped = 0;
  const bool mirrored = placement.determinant() < 0;
  for (unsigned int f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) {  // aiProcess_Triangulate leaves only points and lines besides triangles
      ++dropped;
      continue;
    }
    std::array<std::int32_t, 3> triangle{};
    for (int corner = 0; corner < 3; ++corner) {
      const aiVector3D& v = mesh.mVertices[face.mIndices[corner]];
      // NaN or infinite coordinates: welding and repair would hide them (a NaN vertex makes a
      // "degenerate" triangle that is silently removed); refused with the triangles named.
      if (!(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z))) {
        if (bad.examples.size() < 10 && (bad.examples.empty() || bad.examples.back() != out.triangles.size()))
          bad.examples.push_back(out.triangles.size());
        ++bad.count;
      }
      triangle[corner] = welder.index_of(placement.apply({double(v.x), double(v.y), double(v.z)}));
    }
    if (mirrored) std::swap(triangle[1], triangle[2]);
    out.triangles.push_back(triangle);
  }
  return dropped;
}

/// Text from a damaged file, fit for an error message: bytes outside printable ASCII become '?'.
std::string printable(std::string text) {
  for (char& c : text)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return text;
}

/// Refuses OFF and PLY files whose header declares more vertices or faces than the file has bytes.
/// assimp 5.2 trusts those counts: assimp-testmodels' invalid/OutOfMemory.off declares 353535235358
/// vertices in 309 bytes and takes 16 GB and minutes before it fails. Any encoding needs at least
/// one byte per element, so the bound never refuses a valid file.
void refuse_impossible_counts(const std::string& path) {
  const std::string extension = lower_extension(path);
  if (extension != ".off" && extension != ".ply") return;
  const auto bytes = std::uintmax_t(std::filesystem::file_size(path));
  std::ifstream in(path, std::ios::binary);
  std::string header(4096, '\0');
  in.read(header.data(), std::streamsize(header.size()));
  header.resize(std::size_t(in.gcount()));
  std::istringstream lines(header);
  std::vector<std::string> counts;  // declared element counts, as written
  std::string line;
  bool off_header_seen = false;
  int line_number = 0;
  bool end_seen = false;
  bool format_seen = false, element_seen = false;
  while (std::getline(lines, line)) {
    ++line_number;
    if (extension == ".ply") {
      // assimp 5.2's PLY reader loops forever on damaged headers (the mesh fuzzer found an unknown
      // keyword, a garbled property type, and a garbled element line with a second format line;
      // tests/fuzz/regressions/mesh/ply_*): the header must follow the PLY grammar line by line.
      if (!line.empty() && line.back() == '\r') line.pop_back();
      auto refuse = [&](const std::string& why) {
        throw MeshError(MeshError::Kind::unreadable, path + ": line " + std::to_string(line_number) + " of the PLY header ('" +
                                                         printable(line.substr(0, 60)) + "') " + why +
                                                         ". The file is damaged: re-export it");
      };
      if (std::any_of(line.begin(), line.end(), [](char c) { return static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126; }))
        refuse("holds bytes that are not text");
      std::istringstream keyword_words(line);
      std::vector<std::string> w;
      for (std::string token; keyword_words >> token;) w.push_back(token);
      const std::string keyword = w.empty() ? "" : w[0];
      static const char* const kTypes[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int8",
                                           "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"};
      auto is_type = [&](const std::string& t) { return std::any_of(std::begin(kTypes), std::end(kTypes), [&](const char* k) { return t == k; }); };
      auto is_count = [](const std::string& t) { return !t.empty() && t.size() <= 20 && std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; }); };
      if (line_number == 1) {
        if (keyword != "ply" || w.size() != 1) refuse("must be 'ply'");
        continue;
      }
      if (keyword == "end_header") {
        if (w.size() != 1 || line != "end_header") refuse("must be exactly 'end_header'");
        if (!format_seen || !element_seen) refuse("ends a header without a format line or an element");
        end_seen = true;
        break;
      }
      if (keyword == "comment" || keyword == "obj_info") continue;
      if (keyword == "format") {
        const bool known = w.size() == 3 && (w[1] == "ascii" || w[1] == "binary_little_endian" || w[1] == "binary_big_endian");
        if (!known || format_seen) refuse(format_seen ? "is a second format line" : "must be 'format ascii|binary_little_endian|binary_big_endian 1.0'");
        format_seen = true;
        continue;
      }
      if (keyword == "element") {
        if (w.size() != 3 || !is_count(w[2])) refuse("must be 'element NAME COUNT' with a whole number");
        counts.push_back(w[2]);
        element_seen = true;
        continue;
      }
      if (keyword == "property") {
        const bool valid = element_seen && (w.size() == 3 ? is_type(w[1])
                                                           : w.size() == 5 && w[1] == "list" && is_type(w[2]) && is_type(w[3]));
        if (!valid)
          refuse("must be 'property TYPE NAME' or 'property list TYPE TYPE NAME' after an element; types: char, uchar, short, ushort, "
                 "int, uint, float, double (or int8 ... float64)");
        continue;
      }
      // Free text before the first element is read as a comment (Blender 2.4x writes a
      // "Created by ..." line without the keyword, e.g. assimp-testmodels' PLY/Wuson.ply).
      if (!element_seen) continue;
      refuse("starts with an unknown keyword; valid: ply, format, comment, obj_info, element, property, end_header");
    }
    std::istringstream words(line.substr(0, line.find('#')));
    std::string word;
    // OFF: a keyword ending in "OFF", then the vertex and face counts (on the same line or the next).
    while (words >> word && counts.size() < 2) {
      if (!off_header_seen && word.size() >= 3 && word.compare(word.size() - 3, 3, "OFF") == 0)
        off_header_seen = true;
      else
        counts.push_back(word);
    }
    if (counts.size() >= 2) break;
  }
  if (extension == ".ply" && !end_seen && bytes >= header.size())
    throw MeshError(MeshError::Kind::unreadable, path + ": the PLY header has no end_header in its first 4096 bytes; re-export it");
  for (const std::string& count : counts)
    if (std::strtoull(count.c_str(), nullptr, 10) > bytes)
      throw MeshError(MeshError::Kind::unreadable, path + ": the header declares " + count +
                                                       " elements but the file has only " + std::to_string(bytes) +
                                                       " bytes; the file is damaged, re-export it");
}

/// Checks an STL file's completeness before assimp reads it: assimp reads a file cut between two
/// facets (a copy or a download that stopped) as the facets before the cut, a mesh with a hole
/// and no word. Binary: 84 bytes of header and count, then 50 bytes a facet; fewer bytes than the
/// count needs is a cut. ASCII ("solid" first, and not a binary file of the right size that
/// happens to begin so): every `facet` closed by `endfacet` with three `vertex` lines, and the
/// last word `endsolid` (with its name).
void check_stl_file(const std::string& path) {
  const auto bytes = std::uintmax_t(std::filesystem::file_size(path));
  std::ifstream in(path, std::ios::binary);
  char head[84] = {};
  in.read(head, sizeof head);
  const auto got = std::size_t(in.gcount());
  std::uint32_t count = 0;
  if (got == sizeof head) std::memcpy(&count, head + 80, sizeof count);
  const std::uintmax_t binary_size = 84 + 50 * std::uintmax_t(count);
  const bool looks_ascii = got >= 5 && std::string_view(head, 5) == "solid";
  if (!looks_ascii || (got == sizeof head && bytes == binary_size)) {
    if (got < sizeof head)
      throw MeshError(MeshError::Kind::unreadable, path + ": " + std::to_string(bytes) +
                                                       " bytes, shorter than a binary STL's 84-byte header; the file is damaged, re-export it");
    if (bytes < binary_size)
      throw MeshError(MeshError::Kind::unreadable, path + ": the binary STL declares " + std::to_string(count) + " facets (" +
                                                       std::to_string(binary_size) + " bytes) but the file has " + std::to_string(bytes) +
                                                       " bytes: it was cut after facet " + std::to_string((bytes - 84) / 50) +
                                                       "; re-export or copy it again");
    return;
  }
  in.clear(), in.seekg(0);
  std::string line, last_word;
  int line_number = 0, vertices = 0, open_line = 0;
  bool open = false;
  auto refuse = [&](const std::string& why) {
    throw MeshError(MeshError::Kind::unreadable, path + ": line " + std::to_string(line_number) + " of the ASCII STL: " + why +
                                                     "; the file is damaged or cut, re-export or copy it again");
  };
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream words(line);
    std::string first;
    if (!(words >> first)) continue;
    last_word = first;
    if (first == "facet") {
      if (open) refuse("a facet begins before the facet of line " + std::to_string(open_line) + " ends (no endfacet)");
      open = true, open_line = line_number, vertices = 0;
    } else if (first == "vertex") {
      ++vertices;
    } else if (first == "endfacet") {
      if (!open) refuse("endfacet without its facet");
      if (vertices != 3) refuse("the facet of line " + std::to_string(open_line) + " has " + std::to_string(vertices) + " vertices, not 3");
      open = false;
    }
  }
  if (open) refuse("the file ends inside the facet of line " + std::to_string(open_line));
  if (last_word != "endsolid") refuse("the file ends without endsolid (its last line begins '" + printable(last_word.substr(0, 40)) + "')");
}

/// Checks an OFF file line by line before assimp reads it: assimp 5.2's OFF reader crashes
/// (segmentation fault) on face lines whose vertex count or indices do not fit the declared
/// vertices (fuzzer finding tests/fuzz/regressions/mesh/off_bad_face_crash). Grammar: a keyword
/// ending in OFF, the counts "V F [E]", V vertex lines of at least three numbers, then F face lines
/// "n i_1 ... i_n" with 3 <= n <= 64 and every index in [0, V); '#' starts a comment.
void check_off_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  int line_number = 0;
  auto refuse = [&](const std::string& why) {
    throw MeshError(MeshError::Kind::unreadable, path + ": line " + std::to_string(line_number) + " of the OFF file ('" +
                                                     printable(line.substr(0, 60)) + "') " + why + ". The file is damaged: re-export it");
  };
  std::vector<std::string> pending;  // tokens of the header not yet used
  auto next_tokens = [&]() -> std::vector<std::string> {
    while (std::getline(in, line)) {
      ++line_number;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const std::string text = line.substr(0, line.find('#'));
      std::istringstream words(text);
      std::vector<std::string> w;
      for (std::string token; words >> token;) w.push_back(token);
      if (!w.empty()) return w;
    }
    return {};
  };
  auto integer = [&](const std::string& t, long long& v) {
    if (t.empty() || t.size() > 18 || !std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; })) return false;
    v = std::stoll(t);
    return true;
  };
  auto number = [](const std::string& t) {
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    return end != t.c_str() && *end == '\0' && std::isfinite(v);
  };
  std::vector<std::string> w = next_tokens();
  if (w.empty() || w[0].size() < 3 || w[0].compare(w[0].size() - 3, 3, "OFF") != 0) refuse("must start with OFF");
  w.erase(w.begin());
  if (w.empty()) w = next_tokens();
  long long vertices = 0, faces = 0;
  if (w.size() < 2 || w.size() > 3 || !integer(w[0], vertices) || !integer(w[1], faces)) refuse("must give the counts 'V F [E]'");
  for (long long v = 0; v < vertices; ++v) {
    w = next_tokens();
    if (w.size() < 3 || !number(w[0]) || !number(w[1]) || !number(w[2])) refuse("must be a vertex: three finite numbers");
  }
  for (long long f = 0; f < faces; ++f) {
    w = next_tokens();
    long long n = 0;
    if (w.empty() || !integer(w[0], n) || n < 3 || n > 64 || static_cast<long long>(w.size()) < n + 1)
      refuse("must be a face: 'n i_1 ... i_n' with 3 <= n <= 64");
    for (long long k = 1; k <= n; ++k) {
      long long index = 0;
      if (!integer(w[k], index) || index >= vertices)
        refuse("has a vertex index that is not one of the " + std::to_string(vertices) + " vertices (0-based)");
    }
  }
}

/// The options are checked first: a zero or non-finite scale would collapse or poison every vertex.
void refuse_invalid_options(const std::string& path, const ImportOptions& options) {
  bool options_valid = std::isfinite(options.unit_scale) && options.unit_scale > 0;
  for (int axis = 0; axis < 3; ++axis)
    options_valid = options_valid && std::isfinite(options.scale[axis]) && options.scale[axis] != 0 &&
                    std::isfinite(options.rotate_deg[axis]) && std::isfinite(options.translate[axis]);
  if (!options_valid)
    throw MeshError(MeshError::Kind::invalid_options,
                    path + ": invalid import options: unit_scale must be > 0, scale non-zero, and all values finite");
}

/// Files refused before assimp opens them: B-rep CAD, a missing file, and damaged OFF, PLY and STL files.
void refuse_unreadable_file(const std::string& path) {
  // B-rep CAD is refused by extension, before assimp guesses at it (its STEP reader is for IFC only).
  if (is_brep_cad(path))
    throw MeshError(MeshError::Kind::cad_format,
                    path + ": STEP/IGES is a B-rep CAD format that cannot be read as a mesh; " + kExportAdvice +
                        " and import that file");
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw MeshError(MeshError::Kind::missing,
                    path + ": no such file (expected a mesh file: STL, OBJ, PLY, 3MF, glTF, ...)");

  refuse_impossible_counts(path);
  if (lower_extension(path) == ".off") check_off_file(path);
  if (lower_extension(path) == ".stl") check_stl_file(path);
}

/// The file as assimp reads it with no post-processing; the scene belongs to `importer`.
const aiScene* read_scene(Assimp::Importer& importer, const std::string& path) {
  // Everything but positions and faces is dropped, so JoinIdenticalVertices joins by position only.
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                                          aiComponent_COLORS | aiComponent_TEXCOORDS |
                                                          aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                                          aiComponent_TEXTURES | aiComponent_LIGHTS |
                                                          aiComponent_CAMERAS | aiComponent_MATERIALS);
  // Skeleton-only files (MD5, SMD, BVH) would otherwise get invented bone meshes.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
  const aiScene* scene = nullptr;
  std::string reason;
  try {
    scene = importer.ReadFile(path, 0);
    if (!scene) reason = importer.GetErrorString();
  } catch (const std::exception& exception) {  // assimp catches its own errors; this is belt and braces
    reason = exception.what();
  }
  if (!scene) {
    std::string known;
    importer.GetExtensionList(known);
    throw MeshError(MeshError::Kind::unreadable, path + ": assimp could not read it (" + reason + "); " +
                                                     "export STL, OBJ, PLY, 3MF or glTF (assimp reads: " + known + ")");
  }
  return scene;
}

/// Surfaces present at all? (assimp's scene preprocessor fills mPrimitiveTypes.)
bool has_surfaces(const aiScene& scene) {
  bool found = false;
  for (unsigned int m = 0; m < scene.mNumMeshes; ++m)
    found = found || (scene.mMeshes[m] && (scene.mMeshes[m]->mPrimitiveTypes &
                                           (aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON)));
  return found;
}

/// "7, 12, 40": the examples of `bad`, for an error message.
std::string example_list(const NonFinite& bad) {
  std::string which;
  for (std::size_t t : bad.examples) which += (which.empty() ? "" : ", ") + std::to_string(t);
  return which;
}

/// Non-finite coordinates, before post-processing hides them (joining identical vertices merges
/// a NaN vertex into another, and the repair then drops the "degenerate" triangle silently).
void refuse_non_finite_faces(const aiScene& scene, const std::string& path) {
  NonFinite bad;
  std::size_t face_index = 0;
  for (unsigned int m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    if (!mesh || !mesh->mVertices) continue;
    for (unsigned int f = 0; f < mesh->mNumFaces; ++f, ++face_index) {
      const aiFace& face = mesh->mFaces[f];
      bool finite = true;
      for (unsigned int c = 0; c < face.mNumIndices && face.mIndices; ++c) {
        if (face.mIndices[c] >= mesh->mNumVertices) continue;  // ValidateDataStructure refuses it below
        const aiVector3D& v = mesh->mVertices[face.mIndices[c]];
        finite = finite && std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
      }
      if (finite) continue;
      if (bad.examples.size() < 10) bad.examples.push_back(face_index);
      ++bad.count;
    }
  }
  if (bad.count > 0) {
    const std::string which = example_list(bad);
    throw MeshError(MeshError::Kind::unreadable,
                    path + ": " + std::to_string(bad.count) + " faces have a corner with non-finite coordinates (NaN or "
                        "infinity), e.g. triangles " + which + " (0-based, in file order); the file is damaged: re-export it");
  }
}

/// Validate first (so broken files are refused, not crashed on), then triangulate and join; the
/// scene belongs to `importer`.
const aiScene* validate_and_join(Assimp::Importer& importer, const std::string& path) {
  const aiScene* scene = nullptr;
  std::string reason;
  try {
    scene = importer.ApplyPostProcessing(aiProcess_ValidateDataStructure | aiProcess_RemoveComponent |
                                         aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
    if (!scene) reason = importer.GetErrorString();
  } catch (const std::exception& exception) {
    scene = nullptr;
    reason = exception.what();
  }
  if (!scene)
    throw MeshError(MeshError::Kind::unreadable,
                    path + ": the file is damaged (" + reason + "); re-export it as STL, OBJ, PLY, 3MF or glTF");
  return scene;
}

/// The scene's triangles in metres, placed by the user's options; corners with non-finite
/// coordinates are refused.
TriangleMesh place_triangles(const aiScene& scene, const std::string& path, const ImportOptions& options) {
  // Walk the node hierarchy, placing each referenced mesh by its node's global transform.
  TriangleMesh out;
  out.source = path;
  VertexWelder welder(out.vertices);
  NonFinite bad;
  const Affine placement = from_options(options);
  std::size_t points_and_lines = 0;
  std::vector<std::pair<const aiNode*, Affine>> stack;
  if (scene.mRootNode) stack.emplace_back(scene.mRootNode, placement);
  while (!stack.empty()) {
    const auto [node, parent] = stack.back();
    stack.pop_back();
    const Affine global = compose(parent, from_assimp(node->mTransformation));
    for (unsigned int k = 0; k < node->mNumMeshes; ++k)
      if (node->mMeshes[k] < scene.mNumMeshes)
        points_and_lines += append_mesh(*scene.mMeshes[node->mMeshes[k]], global, welder, out, bad);
    for (unsigned int child = 0; child < node->mNumChildren; ++child)
      if (node->mChildren[child]) stack.emplace_back(node->mChildren[child], global);
  }
  // A scene whose nodes reference no mesh at all: take the meshes as they are.
  if (out.triangles.empty() && points_and_lines == 0)
    for (unsigned int m = 0; m < scene.mNumMeshes; ++m) append_mesh(*scene.mMeshes[m], placement, welder, out, bad);
  if (bad.count > 0) {
    const std::string which = example_list(bad);
    throw MeshError(MeshError::Kind::unreadable,
                    path + ": " + std::to_string(bad.count) + " triangle corners have non-finite coordinates (NaN or infinity), "
                        "e.g. in triangles " + which + " (0-based, in file order); the file is damaged: re-export it");
  }
  return out;
}

}  // namespace

bool has_importable_extension(const std::string& path) {
  // One importer for all queries: constructing one instantiates every format reader.
  static const Assimp::Importer importer;
  const std::string extension = lower_extension(path);
  return !extension.empty() && !is_brep_cad(path) && importer.IsExtensionSupported(extension);
}

TriangleMesh import_mesh(const std::string& path, const ImportOptions& options) {
  refuse_invalid_options(path, options);
  refuse_unreadable_file(path);
  // Read with no post-processing first, so a file without surfaces is told apart from a broken one.
  Assimp::Importer importer;
  const aiScene* scene = read_scene(importer, path);
  const bool surfaces = has_surfaces(*scene);
  const std::string no_triangles =
      path + ": holds no triangles (only points, lines or no geometry); a wall needs a surface: " + kExportAdvice;
  if (!surfaces) throw MeshError(MeshError::Kind::no_triangles, no_triangles);
  refuse_non_finite_faces(*scene, path);
  scene = validate_and_join(importer, path);
  TriangleMesh out = place_triangles(*scene, path, options);
  if (out.triangles.empty()) throw MeshError(MeshError::Kind::no_triangles, no_triangles);
  if (out.vertices.size() > std::size_t(std::numeric_limits<std::int32_t>::max()))
    throw MeshError(MeshError::Kind::unreadable, path + ": more than 2^31 vertices; decimate the mesh before import");
  return out;
}

}  // namespace dem::geometry
