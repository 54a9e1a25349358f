// The types every room of materials/ shares: the material being calibrated and the set-up of one
// experiment. The rooms, lowest first: model/ (the material, its parameters and candidates, the
// library), lab/ (the virtual laboratory and the measurement files it reads), calibration/
// (compare, calibrate, the store, the budget, the ledger), diagnosis/ (which effect is missing);
// each includes only from the rooms below it (tests/check_rooms.cmake).
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "case/spec.h"

namespace dem::materials {

/// The material being calibrated: one particle material with its contact model and its size
/// (and optionally shape), plus the wall materials the tests use and the particle-wall pairs.
struct MaterialModel {
  std::string name;                 ///< e.g. "gravel"
  MaterialSpec particle;            ///< density, E, nu, effect parameters (restitution, friction, ...)
  ContactSpec contact;              ///< the effects switched on
  SizeDistributionSpec diameter;    ///< particle size
  std::vector<ClumpTemplateSpec> shape;  ///< empty: spheres; one template: clumps of it
  std::vector<MaterialSpec> walls;       ///< wall materials by name (steel, ...)
  std::vector<InteractionSpec> wall_pairs;  ///< particle-wall pair parameters
  std::map<std::string, std::pair<double, double>> tunable;  ///< key -> [min, max]
  /// Keys the measurement file gave as measured (inputs, never fitted), in file order.
  std::vector<std::string> known;
  /// Wall-pair keys fitted first to their single-contact tests (calibration/walls_first.cpp): not offered
  /// again as wall-parameter candidates.
  std::vector<std::string> fitted_first;
  double mass_scaling = 1.0, stiffness_scaling = 1.0;  ///< applied to the virtual tests (reported)
  /// [-] Coarse graining of the virtual tests (core/coarse_grain.h): the real apparatus filled
  /// with parcels of coarse_grain x the diameter, each standing for coarse_grain^3 particles, the
  /// contact parameters scaled by the stress-similarity law (--coarse-grain). 1: real particles.
  /// A state of the material in the tests, as the scalings are, rather than an option of one
  /// comparison: every copy a calibration or diagnosis makes of the model (a candidate, the fit)
  /// keeps it, the store keys its simulations by it and the calibrated file records it.
  double coarse_grain = 1.0;
};

/// The set-up of one experiment as the measurement file gives it: numbers (lengths in m,
/// stresses in Pa, speeds in m/s, angles in deg) and words (wall material names, `ends`).
struct TestSetup {
  std::string test;  ///< drop_rebound, bulk_density, angle_of_repose_cylinder, rotating_drum, hopper_discharge, direct_shear
  std::string id;    ///< the experiment's id in its measurement file (errors name it); may be empty
  std::map<std::string, double> numbers;
  std::map<std::string, std::string> words;
  SourceLocation location;  ///< of the experiment in the measurement file, for errors
};

}  // namespace dem::materials
