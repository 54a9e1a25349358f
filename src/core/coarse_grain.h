// Coarse graining ("parcels"): the one place where the scaling law lives. A case gives
// `coarse_grain: F` (F >= 1) on its inlets and particle sets; each particle the engine then moves
// is a parcel standing for F^3 real particles of the same material, F times a real diameter drawn
// from the stated size distribution (the whole distribution scaled by F). An inlet keeps its real
// mass rate (F^3 fewer parcels); a particle set's `count` counts real particles (round(count/F^3)
// parcels, at least 1), its `positions` list parcels.
//
// The law is stress similarity (Bierwisch, Kraft, Riedel & Moseler 2009, J. Mech. Phys. Solids
// 57:10, "Three-dimensional discrete element models for the granular statics and dynamics of
// powders in cavity filling"; Radl, Radeke, Khinast & Sundaresan 2011, "Parcel-based approach for
// the simulation of gas-particle flows", 8th CFD conference Trondheim; Chu, Chen & Yu 2016,
// coarse-grained CFD-DEM, Minerals Eng., for cohesive forces): with the material's density,
// moduli and dimensionless coefficients kept, a bulk of parcels has the real bulk's energy
// density, stresses and velocities when every contact force divided by d^2 (its stress) is the
// real one at the same relative overlap delta/d. Each parameter of each contact effect declares
// how it follows: it is multiplied by F^exponent (ParamSpec::coarse_grain_exponent, written with
// its reason beside each row in src/contact/effects/):
//   0  dimensionless parameters (restitution, friction, rolling friction and damping, ratios,
//      angles, the liquid content as a volume fraction), velocities, the Hertz law's moduli
//      (E, nu: Hertz is self-similar, force ~ E sqrt(R) delta^1.5 ~ F^2 at the same delta/d), and
//      the sjkr cohesion energy density (a force per contact area, already a stress);
//   1  a linear spring's stiffness [N/m] (the same stress then gives the same delta/d), the JKR
//      surface energy [J/m^2] (pull-off 3/2 pi W R* ~ F^2), the liquid's surface tension [N/m]
//      (bridge force 2 pi R gamma ~ F^2); the bridge volume w (V_i + V_j)/n_b then grows as F^3 by
//      itself, and with it the rupture distance as F.
// A parameter that declares nothing is refused when F != 1, never guessed.
// Bulk quantities (mass flow, drive power, wall pressure) are then the real material's and are
// not rescaled; nor is wear: Archard sliding work per area and the Bitter (impact) energy per area
// and time are both linear in the bulk's energy flux onto the wall, which the law keeps.
//
// Rejected alternatives:
//   (a) cohesion scaled at a constant Bond number (cohesive force / particle weight, force ~ F^3):
//       the bulk's cohesive stress, force / d^2, would then grow with F, and a coarse-grained
//       heap would stand steeper than the real one;
//   (b) friction or rolling friction scaled with F (options of some commercial codes): no
//       stress-similarity basis, a coefficient is a ratio of forces that all scale alike; it is a
//       fit of the coarse model, which a calibration at the parcel size does honestly;
//   (c) the real size distribution with fewer particles: not coarse graining, the bulk would be
//       sparser, not the same material in bigger pieces.
// Out of scope: different F in one case (two parcel sizes meeting at a contact would need two
// scalings at once; refused); openings of a few parcel diameters (warned about); what depends on
// sizes finer than a parcel (segregation, fines percolation) is not reproduced.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "case/spec.h"
#include "core/model.h"

namespace dem {

/// An opening of the geometry (an orifice, a chute's width) narrower than this many parcel
/// diameters is warned about: below about 5-6 diameters a stream arches and jams intermittently
/// (Beverloo, Leniger & van de Velde 1961; Zuriguel et al. 2005, Phys. Rev. E 71:051303), where
/// the real material, F times as many of its diameters across, flows.
inline constexpr double kOpeningParcelDiameters = 6.0;

/// The case's one coarse-graining factor F: the coarse_grain that every inlet and particle set
/// gives (1 when there are none). Throws CaseError naming the two entries when they differ (mixed
/// F is out of scope), or one whose factor is not finite or below 1 (a spec built in code).
double case_coarse_grain(const CaseSpec& spec);

/// F^exponent [-], the factor a parameter of that exponent is multiplied by.
double coarse_grain_factor(double coarse_grain, int exponent);

/// The distribution of parcel diameters: every diameter of `real` (fixed value, mean, standard
/// deviation, bounds, discrete values) times F; the fractions unchanged.
SizeDistributionSpec parcel_diameters(const SizeDistributionSpec& real, double coarse_grain);

/// Parcels standing for `real_count` particles: round(real_count / F^3), at least 1.
std::int64_t parcel_count(std::int64_t real_count, double coarse_grain);

/// A particle set or an inlet as parcels: diameters x F, a real `count` turned into parcels
/// (a set's `positions` are parcels already; an inlet's mass rate is the real one).
void make_parcels(ParticleSetSpec& set, double coarse_grain);
void make_parcels(InletSpec& inlet, double coarse_grain);

/// Multiplies each parameter of every pair row by F^exponent (ParamSpec::coarse_grain_exponent),
/// F = model.coarse_grain: after the mixing rules and `interactions:`, before derived values.
/// Throws CaseError when an active effect's parameter declares no exponent.
void scale_pair_parameters(Model& model);

/// Warnings for openings narrower than kOpeningParcelDiameters of the largest parcel: holes of
/// discs (orifices), cylinders and tubes among the walls, and the equipment's design values that
/// are widths of a passage the bulk flows through. Empty when none is found.
std::vector<std::string> narrow_openings(const Model& model);

/// Notes for the set-up log on each library material the case's particles are made of whose
/// calibration ran its virtual tests at another coarse_grain than `coarse_grain`, the case's
/// (CalibrationRecord::coarse_grain): the law above carries a fit from one parcel size to another
/// in principle, but only a comparison at the case's F shows it holds. Never silent: a mismatch
/// of any size is named. Empty when every calibrated material matches.
std::vector<std::string> calibration_coarse_grain_notes(const CaseSpec& spec, double coarse_grain);

/// What coarse graining does in this run, in lines for the set-up log and the run report: F, each
/// set's and inlet's parcel diameters and counts, the parameters scaled and by what factor, what
/// the results are, its limits and the warnings of narrow_openings. Empty when F = 1.
std::vector<std::string> describe_coarse_grain(const CaseSpec& spec, const Model& model);

}  // namespace dem
