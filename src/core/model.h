// The compiled, immutable form of a case: materials, the contact law as an ordered list of
// effects with their mixed per-pair parameters, walls, options. Built once by `compile`; the
// simulation only reads it. Everything that changes is in State (state.h).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "case/spec.h"
#include "contact/effect.h"
#include "contact/mesh.h"
#include "motion/kinematics.h"

namespace dem {

struct Material {
  std::string name;
  double density;         // [kg/m^3]
  double youngs_modulus;  // [Pa]; +inf for a rigid wall
  double poisson_ratio;   // [-]
};

/// An effect switched on by the case, with where its data sit.
struct ActiveEffect {
  const EffectSpec* spec;
  int param_offset;    ///< in a pair row
  int history_offset;  ///< in a contact's history row
  std::array<std::uint8_t, 4> options{};  ///< chosen value index per OptionSpec
};

/// Analytic wall (PlaneWallSpec::Shape): an infinite plane (particles live on the side the normal
/// points to), the inside of an infinite cylinder (axis through `point` along `normal`, radius
/// `radius`), a flat disc or ring about `point` in the plane normal to `normal`, or a tube (a
/// cylinder's surface from `point` along `normal` for `length`); discs and tubes are touched
/// from both sides and have edges. Where it is now is State.
struct PlaneWall {
  using Shape = PlaneWallSpec::Shape;
  std::string name;
  std::array<double, 3> point;     // [m] at t = 0
  std::array<double, 3> normal;    // unit; a cylinder's or tube's axis
  std::array<double, 3> velocity;  // [m/s] set velocity (a servo adds its normal speed)
  int material;
  Shape shape = Shape::plane;
  double radius = 0;  // [m] cylinder, tube; disc: outer radius
  double hole = 0;    // [m] disc: inner radius
  double length = 0;  // [m] tube
  double spin = 0;    // [rad/s] surface turning about the line through point along normal
  bool servo = false;
  double target_stress = 0;  // [Pa]
  double servo_area = 0;     // [m^2]
  double servo_max_speed = 0;  // [m/s]

  bool round() const { return shape == Shape::cylinder || shape == Shape::tube; }

  /// Distance [m] from the surface to x on the particles' side, and the unit normal there
  /// (from the surface towards x); `at` is where the wall's point is now.
  double distance(const double at[3], const double x[3], double n[3]) const {
    const double d[3] = {x[0] - at[0], x[1] - at[1], x[2] - at[2]};
    const double along = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2];
    if (shape == Shape::plane) {
      n[0] = normal[0], n[1] = normal[1], n[2] = normal[2];
      return along;
    }
    const double r[3] = {d[0] - along * normal[0], d[1] - along * normal[1], d[2] - along * normal[2]};
    const double rho = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (shape == Shape::cylinder) {
      for (int a = 0; a < 3; ++a) n[a] = rho > 0 ? -r[a] / rho : 0.0;
      return radius - rho;
    }
    // Disc and tube: the nearest point c of the surface (relative to `at`), then x - c.
    double u[3];  // unit radial direction (any one normal to the axis on the axis itself)
    if (rho > 0) {
      for (int a = 0; a < 3; ++a) u[a] = r[a] / rho;
    } else {
      const double e[3] = {std::abs(normal[0]) < 0.9 ? 1.0 : 0.0, std::abs(normal[0]) < 0.9 ? 0.0 : 1.0, 0.0};
      const double k = e[0] * normal[0] + e[1] * normal[1];
      double norm = 0;
      for (int a = 0; a < 3; ++a) u[a] = e[a] - k * normal[a], norm += u[a] * u[a];
      for (double& v : u) v /= std::sqrt(norm);
    }
    double c_along, c_radius;
    if (shape == Shape::disc) {
      c_along = 0, c_radius = std::clamp(rho, hole, radius);
    } else {
      c_along = std::clamp(along, 0.0, length), c_radius = radius;
    }
    double e[3], dist2 = 0;
    for (int a = 0; a < 3; ++a) e[a] = d[a] - c_along * normal[a] - c_radius * u[a], dist2 += e[a] * e[a];
    const double dist = std::sqrt(dist2);
    if (dist > 0) {
      for (int a = 0; a < 3; ++a) n[a] = e[a] / dist;
    } else {
      for (int a = 0; a < 3; ++a) n[a] = shape == Shape::disc ? normal[a] : -u[a];
    }
    return dist;
  }
};

/// A triangulated wall: its surface in the mesh's own frame, the BVH over it, how it moves.
struct MeshWall {
  std::string name;
  int material;
  std::shared_ptr<const TriangleSurface> surface;
  std::shared_ptr<const TriangleBvh> bvh;
  Motion motion;
  SurfaceVelocitySpec surface_velocity;
  double active_from = 0;  // [s] no contacts before (a wall switched on after the particles settled through it)
};

/// A clump template in its principal frame with the centre of mass at the origin, scaled to a
/// volume-equivalent diameter of 1 m; an instance of diameter d scales lengths by d.
struct ClumpTemplate {
  std::string name;
  std::vector<std::array<double, 3>> centres;  // [m per m of diameter]
  std::vector<double> radii;                   // [m per m of diameter]
  std::array<double, 3> inertia_per_density;   // [m^5] principal moments / density, d = 1 m
  double volume;                               // [m^3] pi/6 by construction
  double bounding_radius;                      // [m per m of diameter]
};

/// A set of particles to create at t = 0, with its material resolved.
struct ParticleSource {
  ParticleSetSpec spec;
  int material;
  int clump = -1;  ///< template index, -1: spheres
  int attached = -1;  ///< plane wall the spheres are glued to, -1: free
};

struct Inlet {
  InletSpec spec;
  int material;
  int clump = -1;
  double interval;  // [s] between insertions
};

/// What the time-step advisor found; printed at start and written with results.
struct TimeStepAdvice {
  double rayleigh_time = 0;          // [s] smallest particle, stiffest material
  double contact_time = 0;           // [s] shortest binary contact at characteristic_velocity
  double characteristic_velocity = 0;  // [m/s]
  double dt = 0;                     // [s] step used
  bool user_given = false;
  bool safe = true;
  std::string report;                // human-readable lines
};

struct Model {
  std::string source;  ///< case file
  std::string title;
  std::vector<Material> materials;

  // Contact law: effects in stage order, parameters per material pair.
  std::vector<ActiveEffect> effects;
  int history_width = 0;           ///< doubles of history per contact
  bool spin_inputs = false;        ///< some effect reads the batch's spin inputs (EffectSpec::reads_spin)
  std::vector<std::uint8_t> history_odd;  ///< per history double: 1 when it changes sign as i and j swap
  int pair_stride = 0;             ///< doubles per pair row: E*, G*, then each effect's params
  std::vector<double> pair_table;  ///< (n_materials^2 x pair_stride)
  double interaction_range = 0;    ///< [m] largest gap at which any effect acts

  std::vector<PlaneWall> planes;
  std::vector<MeshWall> meshes;
  std::vector<ClumpTemplate> clumps;
  std::vector<ParticleSource> sources;
  bool has_attached = false;  ///< some particle source is glued to a wall
  std::vector<Inlet> inlets;
  std::vector<OutletSpec> outlets;
  int domain_outlet = -1;  ///< the outlet with `region: domain` (takes what leaves the domain), or -1
  std::vector<SensorSpec> sensors;  ///< normals and `across` unit, plane thickness > 0
  /// Design values of the equipment (name with unit -> value) and the camera that suits it.
  std::vector<std::pair<std::string, double>> design;
  std::string equipment_camera;

  double dt = 0;                  // [s]
  double duration = 0;            // [s]
  std::array<double, 3> gravity;  // [m/s^2]
  double skin = 0;                // [m] Verlet skin
  double radius_max = 0;          // [m] largest particle radius the case can create
  double radius_min = 0;          // [m]
  std::uint64_t seed = 1;
  int threads = 0;
  // Numerical trouble (SimulationSpec): stop or warn; overlap and energy-rise limits.
  bool stop_on_trouble = true;
  double max_overlap_ratio = 0.5;
  double energy_rise_limit = 0.05;
  bool has_domain = false;
  std::array<double, 3> domain_min{}, domain_max{};  // [m]
  std::array<double, 3> period{};  ///< [m] length of each periodic axis, 0 when not periodic
  double mass_scaling = 1.0;       ///< [-] applied to particle densities (reported, never silent)
  double stiffness_scaling = 1.0;  ///< [-] applied to particle Young's moduli (reported)
  /// [-] Coarse graining F (core/coarse_grain.h): every particle is a parcel standing for F^3 real
  /// ones, F times their diameter, with the pair parameters scaled by the law; 1: real particles.
  /// The sources' and inlets' specs above hold the parcels' diameters and counts.
  double coarse_grain = 1.0;
  /// What coarse graining does in this run, in lines (the set-up log and the run report print
  /// them, with the warnings of narrow openings); empty when coarse_grain is 1.
  std::vector<std::string> coarse_grain_report;
  bool periodic() const { return period[0] > 0 || period[1] > 0 || period[2] > 0; }
  TimeStepAdvice advice;
  OutputSpec output;
  std::vector<std::string> notes;  ///< warnings found while compiling (unused parameters, ...)
  std::uint64_t hash = 0;          ///< of everything above that changes the physics

  int n_materials() const { return static_cast<int>(materials.size()); }
  int pair_type(int a, int b) const { return a * n_materials() + b; }
  const double* pair_row(int type) const { return pair_table.data() + static_cast<size_t>(type) * pair_stride; }
  /// Value of a named parameter for a material pair; NaN when no active effect has it.
  double pair_param(int a, int b, std::string_view key) const;
  int material_index(std::string_view name) const;  ///< -1 when absent
};

/// Triangles of a mesh wall given by file (the geometry library imports, checks and repairs it;
/// the engine does not read CAD itself).
struct TriangleSoup {
  std::vector<std::array<double, 3>> vertices;  // [m]
  std::vector<std::array<std::int32_t, 3>> triangles;
};
using MeshLoader = std::function<TriangleSoup(const MeshWallSpec&)>;

/// Checks the spec and builds the model. Throws CaseError naming file, line and key. Meshes
/// given by file need `loader`; inline meshes do not.
Model compile(const CaseSpec& spec, const MeshLoader& loader = {});

/// The effect documentation table (`demdesign effects`).
std::string describe_effects();

}  // namespace dem
