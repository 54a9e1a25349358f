// Yield loci from direct shear experiments (Groeger & Katterfeld, "Application of the DEM in
// Materials Handling, Part 1": materials compared by the yield loci of shear tests at several
// normal stresses after one pre-shear; the angle of internal friction from the slope, the
// cohesion from the intercept). The linear Mohr-Coulomb locus tau = c + sigma tan(phi) is fitted
// by weighted least squares to measured or simulated points, and a simulated locus is compared
// with the measured one in words that name what would move it.
//
// Which normal stress a point belongs to follows the extraction rule of the direct shear test
// (lab_direct_shear.cpp): peak_shear_stress is sheared at the set-up's `normal_stress` after
// pre-shear at `preshear_stress`, so the peaks of one pre-shear form one yield locus;
// steady_shear_stress is the end of the pre-shear itself, at `preshear_stress`, so the steady
// states of all experiments form one locus over their pre-shear stresses.
//
//   std::vector<YieldLocus> loci = measured_yield_loci(read_measurements("shear.yaml"));
//   loci[0].fit.friction_angle   // [deg]
#pragma once

#include <string>
#include <vector>

#include "lab/measurements.h"

namespace dem::materials {

/// One point of a yield locus.
struct LocusPoint {
  double normal_stress = 0;  // [Pa] sigma
  double shear_stress = 0;   // [Pa] tau
  double error = 0;          // [Pa] standard error of tau (one sigma)
  std::string experiment;    ///< the experiment's id in its measurement file; may be empty
};

/// The linear Mohr-Coulomb locus tau = c + sigma tan(phi) fitted to points by weighted least
/// squares (weights 1/error^2); standard errors from the covariance matrix of (c, tan phi),
/// taken as it is (the errors are absolute, not rescaled by chi^2/dof).
struct YieldLocusFit {
  bool fitted = false;
  std::string reason;               ///< why there is no fit ("" when fitted)
  int points = 0;
  double friction_angle = 0;        // [deg] phi
  double friction_angle_sigma = 0;  // [deg] standard error of phi
  double cohesion = 0;              // [Pa] c, the intercept at sigma = 0
  double cohesion_sigma = 0;        // [Pa] standard error of c
  double correlation = 0;           ///< correlation of phi and c (negative: the locus pivots about its points)
  double chi2 = 0;                  ///< sum of squared normalised residuals about the line
  int dof = 0;                      ///< points - 2
  double chi2_per_dof = 0;          ///< NaN for two points (the line passes through both)
  bool cohesion_zero = false;       ///< c lies within 2 sigma of 0: the points show no cohesion
};

/// Fits tau = c + sigma tan(phi). No fit, with the reason, for fewer than two distinct normal
/// stresses or a point without a finite standard error above zero.
YieldLocusFit fit_yield_locus(const std::vector<LocusPoint>& points);

/// The points of one observable of the direct shear test, measured or simulated, and their fit.
struct YieldLocus {
  std::string observable;        ///< peak_shear_stress or steady_shear_stress
  double preshear_stress = 0;    // [Pa] the pre-shear of a peak locus; 0 for the steady-state locus
  std::vector<LocusPoint> points;  ///< ascending normal stress
  YieldLocusFit fit;
  /// "peak shear stress after pre-shear at 4 kPa", "steady shear stress at the pre-shear stresses".
  std::string label() const;
};

/// One shear stress of a direct shear experiment, measured or simulated, with its standard error.
struct ShearValue {
  std::string experiment;  ///< the experiment's id in the measurement file
  std::string observable;  ///< peak_shear_stress or steady_shear_stress (others are left out)
  double value = 0;        // [Pa]
  double error = 0;        // [Pa] one sigma
};

/// Groups values into yield loci, the normal stress of each taken from its experiment's set-up in
/// `set` (see the header comment): one locus per pre-shear stress for the peaks, one for the
/// steady states. Values of experiments that are not direct shear tests of `set` are left out.
/// Loci in order: peaks by pre-shear stress, then steady states; each fitted.
std::vector<YieldLocus> group_yield_loci(const MeasurementSet& set, const std::vector<ShearValue>& values);

/// The measured yield loci of a measurement file (its direct shear observations).
std::vector<YieldLocus> measured_yield_loci(const MeasurementSet& set);

/// A measured yield locus and the simulated one on the same experiments.
struct LocusComparison {
  YieldLocus measured, simulated;
  std::string words;  ///< compare_yield_loci(measured.fit, simulated.fit)
};

/// Plain words on how a simulated locus differs from the measured one: flatter or steeper
/// (friction angle), higher or lower (cohesion), or within the noise. A difference counts when it
/// exceeds twice the standard errors of both fits combined (sqrt(s_measured^2 + s_simulated^2)).
std::string compare_yield_loci(const YieldLocusFit& measured, const YieldLocusFit& simulated);

}  // namespace dem::materials
