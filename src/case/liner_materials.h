// The liner materials a case names for the wear analysis (`wear: {liners: {MESH: {material:
// NAME, thickness_mm: T}}}`): per material the volume it loses per joule of friction work
// (sliding) and per joule of normal impact energy (impact), each with its source. The table is
// liner_materials.cpp, one row a material; a row added there is a word the case reader accepts
// and the key reference lists. A case may override either coefficient of one liner.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace dem {

/// A liner material and its two wear coefficients.
struct LinerMaterial {
  const char* key;             ///< the word a case uses: "ar400"
  const char* name;            ///< what it is: "AR400 wear plate (400 HBW)"
  /// [m^3/J] volume lost per friction work, sum |F_t . v_slip| dt (the wall records' shear_work):
  /// Archard's k/H over the friction coefficient of the sliding it was measured in.
  double sliding_coefficient;
  /// [m^3/J] volume lost per normal impact energy, sum 1/2 m* v_n^2 at contact starts (the wall
  /// records' impact_energy): 1/epsilon of Bitter's deformation wear.
  double impact_coefficient;
  const char* sliding_source;  ///< where sliding_coefficient comes from, with its conversion
  const char* impact_source;   ///< where impact_coefficient comes from, with its conversion
  const char* note;            ///< "estimate: ..." for a value that is not a published figure; limits of use
};

/// Every row of the table, in its order.
std::span<const LinerMaterial> liner_materials();
/// The row whose key is `key`, or nullptr.
const LinerMaterial* find_liner_material(std::string_view key);
/// The keys in the table's order: the words `material:` accepts.
std::vector<std::string> liner_material_keys();

}  // namespace dem
