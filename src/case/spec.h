// The authoring form of a case: what a YAML file says, with units (SI) and defaults filled in and
// every key checked. `parse_case` reads it; `compile` (model.h) turns it into an immutable Model.
// Tests build a spec from inline YAML text and edit its fields before compiling.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <array>

#include "base/vec3.h"
#include "motion/kinematics.h"

// Forward declaration: the equipment and sweep sections keep their YAML for the generators.
namespace YAML {
class Node;
}

namespace dem {

/// Where a value came from, for error messages: "cases/x.yaml:12:5".
struct SourceLocation {
  std::string file;
  int line = 0;    ///< 1-based; 0 when unknown
  int column = 0;  ///< 1-based
  std::string str() const;
};

/// A case that cannot be run as written. The message names file, line, key and what is valid.
class CaseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The fit a calibrated library material came from (its file's `calibration:` block, written by
/// `demdesign calibrate` / `diagnose`): which parameters were fitted, their values and standard
/// deviations in SI units, their correlation, and how well the model then fitted the measurements.
/// Design runs draw parameter sets from it (value, sigma, correlation: a normal posterior).
struct CalibrationRecord {
  std::string command;       ///< "calibrate" or "diagnose"
  std::string measurements;  ///< the measurement file, as given to the command
  std::string date;          ///< YYYY-MM-DD
  std::string engine;        ///< "demdesign 0.1.0"
  std::vector<std::string> effects;     ///< the contact effects switched on
  std::vector<std::string> parameters;  ///< fitted keys: "friction", "steel.friction" (a wall pair)
  std::vector<double> value, sigma;     ///< per parameter, SI units
  std::vector<std::vector<double>> correlation;  ///< symmetric, unit diagonal, positive semi-definite
  double chi2_per_n = 0;     ///< of the calibrated model against the measurements
  double stiffness_scaling = 1;  ///< factor on Young's modulus the virtual tests used in the fit
  /// [-] The coarse_grain the virtual tests ran at (parcels of F x the diameter; core/coarse_grain.h):
  /// a case at another coarse_grain is told so in its set-up log. 1: real particles.
  double coarse_grain = 1;
  SourceLocation location;
};

/// A rigid particle made of overlapping spheres (the source paper's sphere conglomerates).
struct ClumpTemplateSpec {
  std::string name;
  std::vector<Vec3> centres;    // [m] in the template's frame
  std::vector<double> radii;    // [m]
  SourceLocation location;
};

struct MaterialSpec {
  std::string name;
  double density = 2500.0;        // [kg/m^3]
  double youngs_modulus = 5e7;    // [Pa]; +inf: rigid
  double poisson_ratio = 0.25;    // [-]
  std::map<std::string, double> params;  ///< effect parameters given in the file, by key
  std::map<std::string, SourceLocation> where;  ///< location of each given key
  SourceLocation location;
  // Provenance when the material comes from the library (materials/NAME.yaml):
  std::string library_file;                     ///< "" when defined in the case
  std::string description;
  std::map<std::string, std::string> sources;   ///< key -> where its value comes from
  std::map<std::string, std::pair<double, double>> tunable;  ///< key -> [min, max] for calibration
  /// key -> [min, max] a fitted value of this material plausibly lies in (its class's, with the
  /// source under `sources:`); a calibration names a value outside as a sign of missing physics.
  std::map<std::string, std::pair<double, double>> plausible;
  std::optional<CalibrationRecord> calibration;  ///< when the library file is a calibrated material
  /// The particles' shape a library file gives (`shape: {spheres: [...]}`): the case gains it as a
  /// clump template named after the material, which the material's particle sets and inlets use
  /// unless they name a `clump:` of their own. Empty: spheres.
  std::optional<ClumpTemplateSpec> shape;
};

/// Parameters for one unlike pair that replace the mixing rule.
struct InteractionSpec {
  std::string material_a, material_b;
  std::map<std::string, double> params;
  std::map<std::string, SourceLocation> where;
  SourceLocation location;
};

/// The stages of a contact (contact/effect.h, kStageTable), declared here without the engine's headers.
enum class Stage : std::uint8_t;

/// The effects a case switches on, by stage, with their options.
struct ContactSpec {
  struct Choice {
    std::string model;  ///< effect name; "none" switches the stage off
    std::map<std::string, std::string> options;
    SourceLocation location;
  };
  Choice normal{"hertz", {}, {}}, damping{"restitution", {}, {}}, tangential{"mindlin", {}, {}}, rolling{"none", {}, {}},
      twisting{"none", {}, {}};
  std::vector<Choice> adhesion, extra;

  // A field per stage of kStageTable (contact/effect.h); `single` and `additive` are the one place
  // that maps a stage to its field, so code that walks the stages loops over kStages.
  /// The choice of a single stage; nullptr for an additive one (stage_is_additive).
  const Choice* single(Stage stage) const;
  Choice* single(Stage stage) { return const_cast<Choice*>(std::as_const(*this).single(stage)); }
  /// The list of an additive stage; nullptr for a single one.
  const std::vector<Choice>* additive(Stage stage) const;
  std::vector<Choice>* additive(Stage stage) { return const_cast<std::vector<Choice>*>(std::as_const(*this).additive(stage)); }
  /// What the stage holds, in order: its single choice (also "none"), or each entry of its list.
  std::vector<const Choice*> choices(Stage stage) const;
};

/// Particle diameters: fixed, or drawn from a truncated distribution.
struct SizeDistributionSpec {
  enum class Kind { fixed, normal, uniform, discrete } kind = Kind::fixed;
  double value = 0.004;               // [m] fixed diameter
  double mean = 0.0, std_dev = 0.0;   // [m] normal (by number)
  double min = 0.0, max = 0.0;        // [m] truncation (normal) or range (uniform)
  std::vector<double> values;         // [m] discrete diameters
  std::vector<double> mass_fractions; // [-] discrete, sum to 1
  double largest() const;
  double smallest() const;
};

/// A plane that holds a normal stress by moving along its normal (servo control).
struct ServoSpec {
  double target_stress = 0;  // [Pa] compressive normal stress the wall holds
  double area = 0;           // [m^2] area the stress acts on; 0: the periodic cross-section
  double max_speed = 0;      // [m/s] speed at 100 % stress error; 0: 0.2 % of the smallest radius per step
};

struct PlaneWallSpec {
  std::string name;
  Vec3 point{0, 0, 0};   // [m]
  Vec3 normal{0, 0, 1};  // points into the region particles live in; a cylinder's axis
  Vec3 velocity{0, 0, 0};  // [m/s] constant; a tangential part moves the surface, not the plane
  bool has_servo = false;
  ServoSpec servo;
  std::string material;
  SourceLocation location;
  /// plane: one-sided, infinite; cylinder: its inside, infinite (axis through point along
  /// normal); disc: a flat ring (radius, hole_radius) about point, touched from both sides;
  /// tube: a cylinder's surface from point along the axis for `length`, touched from both sides.
  enum class Shape { plane, cylinder, disc, tube } shape = Shape::plane;
  double radius = 0;       // [m] cylinder, tube; disc: outer radius
  double hole_radius = 0;  // [m] disc: inner radius (0: a full disc)
  double length = 0;       // [m] tube
  /// [rad/s] The surface turns about the line through `point` along `normal` (a cylinder's axis):
  /// a drum's shell and ends. The wall stays where it is; only the contact velocity changes.
  double spin = 0;
};

/// How the surface of a static wall moves (conveyor belts, pulleys): it changes the contact
/// velocity, not the geometry.
struct SurfaceVelocitySpec {
  enum class Kind { none, linear, rotation } kind = Kind::none;
  Vec3 velocity{0, 0, 0};  // [m/s] linear: belt velocity, projected on each triangle's plane
  Vec3 axis{0, 0, 1};      // rotation: unit axis
  Vec3 point{0, 0, 0};     // [m] a point on the axis
  double angular_speed = 0;  // [rad/s]
};

/// A triangulated wall: a CAD file (read by the geometry library) or triangles given inline.
struct MeshWallSpec {
  std::string name;
  std::string file;                       ///< resolved against the case file's folder
  double unit_scale = 1.0;                // file units -> m (0.001 for mm)
  Vec3 scale{1, 1, 1};                    // [-] after unit_scale
  Vec3 rotate_deg{0, 0, 0};               // [deg] about x, then y, then z
  Vec3 translate{0, 0, 0};                // [m] applied last
  std::vector<std::array<double, 3>> vertices;         ///< inline (or generated) triangles [m]
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::string material;
  Motion motion;                          ///< rigid motion of the whole mesh
  SurfaceVelocitySpec surface;
  double active_from = 0;                 // [s] a wall from then on; before, particles pass through it
  SourceLocation location;
};

/// Inserts particles at a mass rate inside a box, without overlaps; or, with `count` and no mass
/// rate, as many as the box takes at each insertion until `count` are in (LIGGGHTS insert/pack).
struct InletSpec {
  std::string name;
  std::string material;
  SizeDistributionSpec diameter;
  std::string clump;              ///< template name, or "" for spheres
  double mass_rate = 0;           // [kg/s] (YAML: mass_rate_tph in t/h, or mass_rate_kgs); 0: fill the box
  std::int64_t count = 0;         ///< particles after which the inlet stops; 0: no limit
  Vec3 region_min{0, 0, 0}, region_max{0, 0, 0};  // [m]
  Vec3 velocity{0, 0, 0};         // [m/s]
  double start = 0, stop = 1e300; // [s]
  double interval = 0;            // [s] between insertions; 0: automatic
  /// Name of an equipment port (e.g. "feed_belt") that supplies region and velocity; "" when the
  /// inlet gives its own region.
  std::string port;
  /// [-] Coarse graining (core/coarse_grain.h): each inserted particle is a parcel standing for
  /// coarse_grain^3 real ones, coarse_grain times their diameter; mass_rate stays the real one and
  /// `count` counts real particles. 1: real particles.
  double coarse_grain = 1.0;
  SourceLocation location;
};

/// Removes particles whose centre enters a box and counts them.
struct OutletSpec {
  std::string name;
  Vec3 region_min{0, 0, 0}, region_max{0, 0, 0};  // [m]
  /// `region: domain`: takes what leaves the domain (simulation.domain) through any face, the
  /// way out of a case whose material falls off the end of the model; such particles are then
  /// product of this outlet, not spillage. At most one outlet per case.
  bool domain = false;
  bool spillage = false;  ///< collects spilled material (the report counts it as spillage, not product)
  SourceLocation location;
};

/// The most lateral bins a box sensor may have (SensorSpec::bins).
inline constexpr int kMostSensorBins = 200;

/// Measures the flow without touching it. A plane sensor gives the mass flow through a plane
/// (within a box), estimated from the particles in a thin slab: Q = sum(m v.n) / thickness. A box
/// sensor gives the mass inside, its mean velocity and the offset of its centroid along `across`
/// from the box centre (the centring of the load on a belt); with `bins`, also a stream profile:
/// per lateral bin across the box, the time-mean mass and the mass-weighted velocity along `along`
/// over the records window (statistics/stream_profile.h, stream_profiles.csv).
struct SensorSpec {
  enum class Kind { plane, box } kind = Kind::box;
  std::string name;
  Vec3 region_min{0, 0, 0}, region_max{0, 0, 0};  // [m] box; for a plane, the part of it counted
  Vec3 point{0, 0, 0};    // [m] plane: a point on it
  Vec3 normal{1, 0, 0};   // plane: unit normal, flow along it counts positive
  double thickness = 0;   // [m] plane: slab thickness; 0: twice the largest particle diameter
  Vec3 across{0, 1, 0};   // box: unit lateral axis for the centring offset and the bins
  int bins = 0;           ///< box: equal lateral bins along `across` for a stream profile; 0: none
  /// box: unit flow direction the bins' velocity is taken along and the depth's length is measured
  /// along (YAML default: across x up, the horizontal perpendicular to `across`).
  Vec3 along{1, 0, 0};
  SourceLocation location;
};

/// A parametric equipment generator named in the case (`equipment: {transfer_chute: {...}}`). The
/// spec keeps its YAML; the equipment library (equipment/) expands it into meshes with their
/// motions, ports for inlets, outlets and sensors before the case is compiled.
struct EquipmentSpec {
  std::string type;                          ///< transfer_chute, screw_conveyor, bucket_elevator, belt_conveyor
  std::shared_ptr<const YAML::Node> params;  ///< the map under the type key
  std::string file;                          ///< case file, for errors and relative paths
  SourceLocation location;
  /// [m] the largest particle diameter the case's inlets and particle sets draw, which openings
  /// and beds are checked against; filled by equipment::expand_equipment; 0: not known (unchecked).
  double largest_particle = 0;
};

struct ParticleSetSpec {
  std::string material;
  std::string clump;  ///< template name, or "" for spheres; diameter then scales the template
  SizeDistributionSpec diameter;
  std::vector<Vec3> positions;  ///< explicit centres [m]; else `count` random in `region`
  int64_t count = 0;
  Vec3 region_min{0, 0, 0}, region_max{0, 0, 0};  // [m] box
  Vec3 velocity{0, 0, 0};          // [m/s]
  Vec3 angular_velocity{0, 0, 0};  // [rad/s]
  /// Name of a plane wall the spheres are glued to (`attach_to: top`): they move with the wall
  /// and load it with their contact forces (rough plates); "" for free particles.
  std::string attach_to;
  /// [-] Coarse graining (core/coarse_grain.h): each particle is a parcel standing for
  /// coarse_grain^3 real ones, coarse_grain times their diameter; `count` counts real particles,
  /// `positions` lists parcels. 1: real particles.
  double coarse_grain = 1.0;
  SourceLocation location;
};

/// The largest coarse_grain a case may give (inlets, particle sets): far beyond any published
/// use (factors of 2-20), low enough that a mistyped value is an error.
inline constexpr double kMostCoarseGrain = 1000.0;

/// Fewer steps than this in the shortest contact make a step unsafe (timestep.h).
inline constexpr double kMinStepsPerContact = 8.0;

struct SimulationSpec {
  double duration = 1.0;          // [s]
  double time_step = 0.0;         // [s]; 0: chosen by the advisor
  double rayleigh_fraction = 0.2; // auto step as a fraction of the Rayleigh time
  /// The auto step also keeps at least this many steps in the shortest contact at the
  /// characteristic velocity (the safety limit is 8).
  double steps_per_contact = 20.0;
  bool refuse_unsafe_step = true; // false: warn and run
  double characteristic_velocity = 0.0;  // [m/s] impact speed for the contact-time check; 0: estimate
  Vec3 gravity{0, 0, -9.81};      // [m/s^2]
  uint64_t seed = 1;
  int threads = 0;                // 0: OpenMP default
  double skin = 0.0;              // [m] Verlet skin; 0: a quarter of the smallest diameter
  bool has_domain = false;        // particles leaving the domain box are removed and counted
  Vec3 domain_min{0, 0, 0}, domain_max{0, 0, 0};
  bool periodic[3] = {false, false, false};  // along x, y, z: the domain wraps around
  double mass_scaling = 1.0;      // [-] particle densities multiplied by this (quasi-static tests)
  double stiffness_scaling = 1.0; // [-] Young's moduli of particle materials multiplied by this
  /// Numerical trouble (NaN, overlap beyond max_overlap_ratio of a radius, energy rising by more
  /// than energy_rise_limit of the energy scale without a source): stop the run, or warn and go on.
  bool stop_on_trouble = true;     // YAML: numerical_trouble: stop | warn
  double max_overlap_ratio = 0.5;  // [-] of the smaller radius
  double energy_rise_limit = 0.05; // [-]
};

struct OutputSpec {
  std::string directory = "out";  ///< relative to the working directory
  int64_t scalars_every = 0;      ///< steps between rows of scalars.csv; 0: about 200 rows
  double progress_seconds = 2.0;  ///< wall-clock seconds between progress lines
  double frames_every = 0;        ///< [s] simulated time between HDF5 particle frames; 0: 20 frames
  double checkpoint_every = 0;    ///< [s] simulated time between checkpoints; 0: none but checkpoint_seconds'
  /// [s] wall-clock time between checkpoints (beside checkpoint_every), so that a killed run
  /// loses at most this much computing; 0: none.
  double checkpoint_seconds = 600;
  /// [s] wall-clock time between saves of the rows computed so far (scalars.csv, events.csv,
  /// each replaced whole, never torn); a killed run loses at most this much of its rows; 0: saved
  /// only at checkpoints and at the end.
  double rows_seconds = 5;
  double records_from = 0;        ///< [s] wall records (pressure, wear inputs) accumulate from here on
  /// Images of the flow: every render_every-th particle frame (0: the last frame only).
  int render_every = 0;
  std::string render_camera;             ///< side, front, top, iso; "": the equipment's preset, else iso
  /// An explicit camera (`camera: {eye, target, up, fov_deg}`) instead of a preset.
  bool has_camera_pose = false;
  Vec3 camera_eye{0, -1, 0}, camera_target{0, 0, 0}, camera_up{0, 0, 1};  // [m]
  double camera_fov_deg = 35;                                               // [deg] vertical
  std::string render_colour = "speed";   ///< speed, radius, material
  int render_width = 1280, render_height = 720;  // [px]
};

/// [h] Hours of operation a year when a case gives none (`wear.operating_hours_per_year`): about
/// two shifts a day, 250 days a year; the report states it as an assumption.
constexpr double kDefaultOperatingHoursPerYear = 6000.0;
/// [h] The most hours a year has (a leap year, 366 x 24).
constexpr double kHoursInALeapYear = 8784.0;

/// The liner of one mesh, or of every mesh without its own (`wear.liners.default`).
struct LinerSpec {
  std::string material;             ///< a key of the liner-material table (case/liner_materials.h)
  double thickness = 0;             ///< [m] wearable thickness (`thickness_mm` / 1000)
  double sliding_coefficient = 0;   ///< [m^3/J] volume per friction work: the material's unless given
  double impact_coefficient = 0;    ///< [m^3/J] volume per normal impact energy: the material's unless given
  SourceLocation location;          ///< of the entry
};

/// `wear`: how long the plant runs a year and what lines each mesh, for the liner life.
struct WearSpec {
  double operating_hours_per_year = kDefaultOperatingHoursPerYear;  ///< [h]
  bool hours_given = false;  ///< false: the default, which the report states as an assumption
  /// Per mesh name, or "default" for every mesh without its own that has no surface velocity.
  std::map<std::string, LinerSpec> liners;
};

struct CaseSpec {
  std::string path;  ///< the file it was read from ("<inline>" for text)
  std::string title;
  SimulationSpec simulation;
  std::vector<MaterialSpec> materials;
  std::vector<InteractionSpec> interactions;
  ContactSpec contact;
  std::vector<PlaneWallSpec> planes;
  std::vector<MeshWallSpec> meshes;
  std::vector<ClumpTemplateSpec> clumps;
  std::vector<ParticleSetSpec> particles;
  std::vector<InletSpec> inlets;
  std::vector<OutletSpec> outlets;
  std::vector<SensorSpec> sensors;
  std::optional<EquipmentSpec> equipment;
  /// Design values the report shows (written by the equipment generator): name -> value with
  /// unit in the name, e.g. "receiving_belt_speed_m_s".
  std::vector<std::pair<std::string, double>> design;
  /// Render camera preset suggested by the equipment ("" when none).
  std::string equipment_camera;
  /// Sliding wear coefficient [m^3/J] (volume per friction work) of each named mesh
  /// (`wear_coefficients: {hood: 2.0e-13, default: 1.0e-13}`; "default" applies to meshes not
  /// named that have no surface velocity). The older form of a liner with no material, no
  /// thickness and no impact wear; a name is in this map or in wear.liners, not both.
  std::map<std::string, double> wear_coefficients;
  WearSpec wear;  ///< operating hours and liners (`wear:`)
  OutputSpec output;
};

/// Finds the file of a library material (`materials: {NAME: {library: FILE}}`): FILE.yaml for the
/// case file `case_file`, or an empty path after adding each place it looked to `searched`.
/// The case reader looks in the case's own folders first (the case's folder, its materials/ and
/// ../materials/), then asks the lookup it was given. The engine does not know where a material
/// library lives: a program that has one passes its lookup to the readers below
/// (dem::materials::library_lookup, materials/model/library.h). Rejected: one lookup set for the
/// whole process at start-up, with which a case found a material or not depending on what the
/// process had read before (reading a material file set it); and a default here that searches
/// the shipped library, which would make the engine know where the library lives.
using LibraryLookup = std::function<std::filesystem::path(const std::string& file, const std::string& case_file, std::string& searched)>;

/// Reads and checks a case file. Throws CaseError naming file, line and key. `library`: where
/// `library:` materials are looked for beyond the case's own folders (empty: nowhere else).
CaseSpec parse_case_file(const std::string& path, const LibraryLookup& library = {});
/// Same for an already loaded YAML tree (sweep variants: the case with a parameter replaced);
/// `file` names it in errors and resolves relative paths.
CaseSpec parse_case_node(const YAML::Node& root, const std::string& file, const LibraryLookup& library = {});

/// Reads a size distribution from the map that holds it under `key`: `diameter:` of inlets, particle
/// sets and measurement files, `size:` of a material file.
class MapReader;
SizeDistributionSpec read_size_distribution(MapReader& parent, const std::string& file, const std::string& key = "diameter");
/// Reads a `motion:` value (kinematics.h): a single part map or a list of part maps (null: no
/// motion). `file` and `key_path` ("meshes.drum.motion") name the value in errors; `base_dir`
/// resolves relative CSV paths (the case file's folder). Throws CaseError naming file, line and key.
Motion read_motion(const YAML::Node& node, const std::string& file, const std::string& key_path,
                   const std::string& base_dir);
/// Same for YAML text (tests keep their model inline); `name` stands in for the file name.
CaseSpec parse_case_text(const std::string& text, const std::string& name = "<inline>", const LibraryLookup& library = {});

}  // namespace dem
