#include "bad_input.h"
#include "model/material_model.h"
#include "lab/measurements.h"

namespace dem::fuzz {

namespace {

/// A plain 6 mm bead with a steel wall: the material the set-ups are checked against (as
/// `compare` checks them against the user's material before any simulation).
materials::MaterialModel beads() {
  materials::MaterialModel m;
  m.name = m.particle.name = "beads";
  m.particle.density = 2500, m.particle.youngs_modulus = 1e7, m.particle.poisson_ratio = 0.25;
  m.particle.params = {{"restitution", 0.5}, {"friction", 0.4}};
  m.diameter.kind = SizeDistributionSpec::Kind::fixed;
  m.diameter.value = 0.006;
  MaterialSpec steel;
  steel.name = "steel", steel.density = 7800, steel.youngs_modulus = 2e11, steel.poisson_ratio = 0.3;
  m.walls.push_back(steel);
  InteractionSpec pair;
  pair.material_a = m.name, pair.material_b = "steel";
  pair.params = {{"restitution", 0.5}, {"friction", 0.4}};
  m.wall_pairs.push_back(pair);
  return m;
}

}  // namespace

std::string read_measurement_text(const std::string& text) {
  try {
    const materials::MeasurementSet set = materials::parse_measurements(text, "fuzz_measurements.yaml");
    materials::MaterialModel model = beads();
    materials::apply_measured(model, set);
    materials::check_experiments(model, set, {});
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

}  // namespace dem::fuzz
