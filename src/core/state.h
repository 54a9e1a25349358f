// Everything that changes during a run. Particle data are columns (struct of arrays) indexed by
// the particle's current slot; slots are re-sorted in space when the neighbour list is rebuilt,
// so anything that must follow a particle uses its `id`.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace dem {

/// Contacts that may interact: pairs closer than interaction range + skin at the last rebuild.
/// Particle pairs are owned by the lower slot i (sorted by i); wall pairs have j = wall index.
/// Per pair: 8 bytes of indices + history_width doubles.
struct ContactList {
  std::vector<std::int32_t> i, j;
  std::vector<double> history;  ///< (size() x history_width)
  std::size_t size() const { return i.size(); }
  void clear() { i.clear(), j.clear(), history.clear(); }
};

/// Rigid bodies made of several spheres (clumps); free spheres are not bodies. Per body:
/// 21 doubles + 8 bytes = 176 bytes.
struct Bodies {
  std::vector<double> x, y, z;          // [m] centre of mass
  std::vector<double> vx, vy, vz;       // [m/s]
  std::vector<double> qw, qx, qy, qz;   // orientation, principal frame -> world (unit quaternion)
  std::vector<double> lx, ly, lz;       // [kg m^2/s] angular momentum about the centre, world frame
  std::vector<double> fx, fy, fz;       // [N] total force at the last evaluation
  std::vector<double> tx, ty, tz;       // [N m] total torque about the centre
  std::vector<double> mass;             // [kg]
  std::vector<double> ix, iy, iz;       // [kg m^2] principal moments
  std::vector<std::int64_t> id;
  std::size_t size() const { return x.size(); }
};

/// Plane walls as they are now (the model holds where they started). Per wall: 9 doubles.
struct WallStates {
  std::vector<double> px, py, pz;  // [m] a point on the plane
  std::vector<double> vx, vy, vz;  // [m/s] velocity of the surface
  std::vector<double> fx, fy, fz;  // [N] force the particles exert on the wall, last evaluation
};

/// Bookkeeping of an inlet: reproducible draws and the mass delivered so far.
struct InletState {
  std::uint64_t random;       ///< splitmix64 state
  double inserted_mass = 0;   // [kg]
  std::int64_t inserted = 0;  ///< particles
  double next_time = 0;       // [s]
  double pending_diameter = 0;  // [m] drawn, not yet placed (0: none)
  std::int64_t failed = 0;    ///< insertions given up because the region was full
};

struct OutletState {
  double removed_mass = 0;  // [kg]
  std::int64_t removed = 0;
};

/// Contacts of each particle with mesh walls: up to kSlots per particle, each with the
/// triangle, the contact point in the mesh's frame (to recognise the contact next step, also
/// on a neighbouring triangle) and its history. Per particle: 1 + 6 x (8 + 24 + 8 w) bytes.
struct MeshContacts {
  static constexpr int kSlots = 6;
  std::vector<std::uint8_t> count;           // (n)
  std::vector<std::int32_t> mesh, triangle;  // (n x kSlots)
  std::vector<double> px, py, pz;            // [m] (n x kSlots), mesh frame
  std::vector<double> history;               // (n x kSlots x history_width)
};

/// What each mesh triangle has received, summed over the run (differences between two times
/// give the rates over that interval). Per triangle: 8 doubles.
struct TriangleRecords {
  std::vector<double> normal_impulse;  // [N s] integral of the normal force
  std::vector<double> shear_impulse;   // [N s] integral of the tangential force magnitude
  std::vector<double> shear_work;      // [J] friction work, sum |Ft . v_slip| dt (Archard wear input)
  std::vector<double> impacts;         // [-] contacts that started on the triangle
  std::vector<double> impact_energy;   // [J] sum of 1/2 m* vn^2 at the start of each contact
  /// [N s] Integral of the force the particles put on the triangle (normal and friction), in the
  /// mesh's own frame: the frame its vertices are stored in, which its pose places in the world.
  /// Rejected: the world frame, in which the mean load on a turning part says nothing of where it
  /// acts on the part.
  std::vector<double> force_impulse_x, force_impulse_y, force_impulse_z;

  /// Every column, for code that treats them alike (sizing, zeroing, packing, summing).
  std::array<std::vector<double>*, 8> columns() {
    return {&normal_impulse, &shear_impulse, &shear_work, &impacts, &impact_energy, &force_impulse_x, &force_impulse_y, &force_impulse_z};
  }
  std::array<const std::vector<double>*, 8> columns() const {
    return {&normal_impulse, &shear_impulse, &shear_work, &impacts, &impact_energy, &force_impulse_x, &force_impulse_y, &force_impulse_z};
  }
};

/// Per mesh, from the last force evaluation.
struct MeshLoads {
  std::vector<double> fx, fy, fz;  // [N] force of the particles on the mesh
  std::vector<double> tx, ty, tz;  // [N m] torque about the mesh's motion origin
  std::vector<double> power;       // [W] rate of work the mesh does on the particles
  /// The seven loads above integrated over the steps since the last row of scalars, 7 a mesh in
  /// that order ([N s], [N m s], [J]), and that time [s]: a row reports their mean over its
  /// interval, not the last step's values. Rejected: the last step's values, which a feed that
  /// inserts at the rows' own period aliases (a stream of 2 kg/s onto a belt, inserted and sampled
  /// every 100 steps, read 21 % below m v).
  std::vector<double> interval;
  double interval_time = 0;
  /// Adds this step's loads, held for dt [s].
  void integrate(double dt) {
    const size_t meshes = fx.size();
    interval.resize(7 * meshes, 0.0);
    const std::vector<double>* columns[7] = {&fx, &fy, &fz, &tx, &ty, &tz, &power};
    for (size_t m = 0; m < meshes; ++m)
      for (size_t c = 0; c < 7; ++c) interval[7 * m + c] += (*columns[c])[m] * dt;
    interval_time += dt;
  }
  /// Load c (0-6: fx, fy, fz, tx, ty, tz, power) of mesh m: its mean since the last row, or the
  /// last step's value before any step was integrated.
  double mean(size_t m, size_t c) const {
    if (interval_time > 0 && 7 * m + c < interval.size()) return interval[7 * m + c] / interval_time;
    const std::vector<double>* columns[7] = {&fx, &fy, &fz, &tx, &ty, &tz, &power};
    return (*columns[c])[m];
  }
  /// A row was written: the next one averages from here.
  void restart_interval() { std::fill(interval.begin(), interval.end(), 0.0), interval_time = 0; }
};

/// The stream profiles of the box sensors with bins (SensorSpec::bins), integrated over time from
/// output.records_from on (statistics/stream_profile.h): each row of scalars adds each bin's mass
/// and momentum along the flow, held for the time since the row before. The rows' parts are summed
/// over the ranks of a decomposed run before any rank integrates them, so every rank holds the
/// same values, as it holds the time. 2 doubles a bin.
struct StreamProfiles {
  std::vector<double> mass_time;      // [kg s] (bins of the binned sensors in the model's order) integral of each bin's mass
  std::vector<double> momentum_time;  // [kg m] integral of each bin's momentum along its sensor's `along`
  double window = 0;                  // [s] time integrated so far
  double last_row_time = 0;           // [s] of the last row seen
  bool has_row = false;               ///< a row has been seen (the first only starts the clock)
};

/// Buffers State::permute gathers columns into, one per element type and column length: a
/// column is swapped with its buffer, so buffers shared by columns of different lengths would
/// hand every column the capacity of the longest.
struct PermuteScratch {
  std::vector<double> f64, slots_f64, history;  // per particle, per mesh slot, mesh slot histories
  std::vector<std::int32_t> i32, slots_i32;
  std::vector<std::int64_t> i64;
  std::vector<std::uint8_t> u8;
};

struct State {
  double time = 0.0;  // [s]
  std::int64_t step = 0;
  std::int64_t next_id = 0;
  std::int64_t lost = 0;  ///< particles removed because they left the domain
  double lost_mass = 0;   // [kg] of those particles (spillage)
  /// The last particle that left the domain, for the run's warning (not checkpointed).
  struct LostParticle {
    std::int64_t id = -1;
    double x = 0, y = 0, z = 0, vx = 0, vy = 0, vz = 0;
  } last_lost;
  /// The first particle each outlet removed and the first that left the domain, with the time
  /// [s] of the positions they were removed at (-1: none yet), for the run's first-arrival
  /// times (events.h); not checkpointed: a resumed run keeps its events in events.csv.
  struct Removal {
    double time = -1;
    LostParticle particle;
  };
  std::vector<Removal> first_removed;  ///< per outlet (sized when the first is removed)
  Removal first_lost;

  // Particles (n): hot columns. 18 doubles + 16 bytes = 160 bytes a particle.
  std::vector<double> x, y, z;     // [m] centre
  std::vector<double> vx, vy, vz;  // [m/s]
  std::vector<double> wx, wy, wz;  // [rad/s]
  std::vector<double> fx, fy, fz;  // [N] total force at the last evaluation
  std::vector<double> tx, ty, tz;  // [N m] total torque at the last evaluation
  std::vector<double> radius;      // [m]
  std::vector<double> inv_mass;    // [1/kg]
  std::vector<double> inv_inertia; // [1/(kg m^2)]
  std::vector<std::int32_t> material;
  std::vector<std::int64_t> id;    ///< persistent, never reused
  std::vector<std::int32_t> body;  ///< clump index, -1 for a free sphere
  /// Plane wall the sphere is glued to (moves rigidly with it, its contact forces load the
  /// wall: the rough plates of a shear cell), -1 for a free sphere.
  std::vector<std::int32_t> attached;
  /// [m] centre in the body's principal frame. Empty until a sphere is attached to a body
  /// (then one entry per particle, 0 for free spheres): 24 bytes a particle that a run of free
  /// spheres does not hold.
  std::vector<double> offset_x, offset_y, offset_z;
  bool has_offsets() const { return !offset_x.empty(); }

  Bodies bodies;
  WallStates walls;
  std::vector<InletState> inlets;
  std::vector<OutletState> outlets;

  ContactList pairs;       ///< particle-particle
  ContactList wall_pairs;  ///< particle-plane wall
  MeshContacts mesh_contacts;
  /// Triangles near each particle at the last rebuild: (mesh, triangle) entries
  /// mesh_candidates[candidate_begin[p] .. candidate_begin[p+1]).
  std::vector<std::int32_t> candidate_begin;
  std::vector<std::array<std::int32_t, 2>> mesh_candidates;
  double lists_built_time = 0;  ///< [s] time of the last rebuild (meshes move)
  /// [m/s] The velocity of the spheres' common drift since the last rebuild, where the lists
  /// follow it (neighbors.h, lists_follow_drift), else zero.
  std::array<double, 3> lists_drift_velocity = {0.0, 0.0, 0.0};
  std::vector<TriangleRecords> records;  ///< per mesh
  MeshLoads mesh_loads;
  StreamProfiles stream_profiles;
  /// Positions at the last rebuild of the contact lists: the lists stay valid until a sphere
  /// has used up its share of the skin from here (DriftLimits, verlet.h). Part of the state so
  /// a restart rebuilds when the uninterrupted run would.
  std::vector<double> x_built, y_built, z_built;

  /// Whether particles carry mesh-contact slots (only when the model has meshes), and the
  /// doubles of history per slot; set by initial_state.
  bool has_meshes = false;
  std::size_t mesh_history_width = 0;

  /// Under domain decomposition (domain.h) the last `ghosts` slots are copies of particles other
  /// ranks own, near this rank's subdomain: they are contact partners, never integrated, never
  /// in a wall or mesh contact, never counted. 0 otherwise. Not part of a checkpoint.
  std::size_t ghosts = 0;

  std::size_t size() const { return x.size(); }
  std::size_t owned() const { return x.size() - ghosts; }
  /// Appends a sphere at rest state; returns its slot.
  std::size_t add_sphere(double px, double py, double pz, double r, double density, int mat);
  /// Reorders particle slots: new slot k holds old slot order[k]. Contact lists are not touched.
  /// The columns are gathered into `scratch` and swapped with it (kept by the caller between
  /// calls: a rebuild allocates nothing once it has grown), and into x_built, y_built and
  /// z_built, which are left holding no positions: the lists must be rebuilt.
  void permute(const std::vector<std::int32_t>& order, PermuteScratch& scratch);
  void permute(const std::vector<std::int32_t>& order) {
    PermuteScratch scratch;
    permute(order, scratch);
  }
  /// Keeps only slots with keep[k] != 0 (contact lists are not touched). Bodies none of whose
  /// spheres remain are removed and the others renumbered.
  void compact(const std::vector<std::uint8_t>& keep);
  /// Appends a clump body; its spheres are added with add_sphere and `attach`ed.
  std::size_t add_body(double px, double py, double pz, const double q[4], double mass, const double principal[3]);
  void attach(std::size_t sphere, std::size_t body, double ox, double oy, double oz);
  /// One particle's data (its columns and mesh contacts) as doubles, to move it between the
  /// ranks of a decomposed run (ids and indices are exact in a double); unpack appends it.
  std::size_t record_size() const;
  void pack(std::size_t slot, std::vector<double>& out) const;
  void unpack(const double* in);
  /// The same for a clump body (its spheres are packed one by one); unpack_body appends it and
  /// returns its index.
  static constexpr std::size_t kBodyRecord = 24;
  void pack_body(std::size_t body, std::vector<double>& out) const;
  std::size_t unpack_body(const double* in);
};

}  // namespace dem
