// The readers of a case's sections, shared by the files of the case reader: spec.cpp reads the
// top level and calls them. Internal to the case room; the engine's interface is spec.h.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "case/spec.h"
#include "case/yaml_check.h"

namespace dem::spec_reading {

// Materials and the contact model (spec_materials.cpp).
void read_effect_params(MapReader& map, const std::vector<std::string>& fixed, std::map<std::string, double>& params,
                        std::map<std::string, SourceLocation>& where);
MaterialSpec read_material(const std::string& name, const YAML::Node& node, const std::string& file, const std::string& path);

/// A library material: materials/NAME.yaml with `properties` (as a case material), `sources`
/// (provenance of each value), `description`, `walls` (pair parameters against wall materials),
/// `contact` (the contact model it was calibrated with), `tunable` ranges and a typical `size`.
struct LibraryMaterial {
  MaterialSpec material;
  YAML::Node contact;  ///< null when the file has none
  std::string file;
  std::vector<std::pair<std::string, YAML::Node>> walls;
};

/// `lookup`: where it is looked for after the case's own folders (LibraryLookup, spec.h).
LibraryMaterial read_library_material(const std::string& name, MapReader& entry, const std::string& case_file, const LibraryLookup& lookup);
ContactSpec read_contact(const YAML::Node& node, const std::string& file);

// Equipment, meshes and walls (spec_walls.cpp).
EquipmentSpec read_equipment(const YAML::Node& node, const std::string& file);
MeshWallSpec read_mesh(const YAML::Node& node, const std::string& file, size_t index);
PlaneWallSpec read_wall(const YAML::Node& node, const std::string& file, size_t index);

// Particles, inlets, outlets and sensors (spec_particles.cpp).
/// A clump template `{spheres: [{centre, diameter}, ...]}`; `path` names it in errors
/// ("clumps.NAME" in a case, "shape" in a material file).
ClumpTemplateSpec read_clump(const std::string& name, const YAML::Node& node, const std::string& file, const std::string& path);
InletSpec read_inlet(const YAML::Node& node, const std::string& file, size_t index);
OutletSpec read_outlet(const YAML::Node& node, const std::string& file, size_t index);
SensorSpec read_sensor(const YAML::Node& node, const std::string& file, size_t index);
ParticleSetSpec read_particles(const YAML::Node& node, const std::string& file, size_t index);

}  // namespace dem::spec_reading
