#include "core/particles.h"

#include "base/parallel.h"
#include "bodies/rigid_body.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>

namespace dem {

std::uint64_t Random::next() {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

double Random::uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

double Random::normal() {
  const double u1 = 1.0 - uniform(), u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

double draw_diameter(const SizeDistributionSpec& d, Random& random) {
  using Kind = SizeDistributionSpec::Kind;
  switch (d.kind) {
    case Kind::fixed: return d.value;
    case Kind::uniform: return d.min + random.uniform() * (d.max - d.min);
    case Kind::normal:
      for (;;) {  // truncated by rejection
        const double x = d.mean + d.std_dev * random.normal();
        if (x >= d.min && x <= d.max) return x;
      }
    case Kind::discrete: {
      // Mass fractions to number fractions: n_k ~ f_k / d_k^3.
      double total = 0;
      for (size_t k = 0; k < d.values.size(); ++k) total += d.mass_fractions[k] / std::pow(d.values[k], 3);
      double u = random.uniform() * total;
      for (size_t k = 0; k < d.values.size(); ++k) {
        u -= d.mass_fractions[k] / std::pow(d.values[k], 3);
        if (u < 0) return d.values[k];
      }
      return d.values.back();
    }
  }
  return d.value;
}

namespace {

/// Hash grid of placed spheres for overlap checks during placement.
class PlacementGrid {
 public:
  explicit PlacementGrid(double cell) : cell_(cell) {}
  void add(const Vec3& c, double r) {
    cells_[key(c)].push_back(centres_.size());
    centres_.push_back({c, r});
  }
  bool free(const Vec3& c, double r) const {
    const long ix = index(c.x()), iy = index(c.y()), iz = index(c.z());
    for (long dz = -1; dz <= 1; ++dz)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dx = -1; dx <= 1; ++dx) {
          const auto it = cells_.find(pack(ix + dx, iy + dy, iz + dz));
          if (it == cells_.end()) continue;
          for (size_t k : it->second) {
            const double reach = centres_[k].second + r;
            if ((centres_[k].first - c).squaredNorm() < reach * reach) return false;
          }
        }
    return true;
  }

 private:
  long index(double v) const { return static_cast<long>(std::floor(v / cell_)); }
  static std::uint64_t pack(long x, long y, long z) {
    return (static_cast<std::uint64_t>(x & 0x1fffff) << 42) | (static_cast<std::uint64_t>(y & 0x1fffff) << 21) |
           static_cast<std::uint64_t>(z & 0x1fffff);
  }
  std::uint64_t key(const Vec3& c) const { return pack(index(c.x()), index(c.y()), index(c.z())); }
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<size_t>> cells_;
  std::vector<std::pair<Vec3, double>> centres_;
};

bool clear_of_walls(const Model& model, const State& state, const Vec3& c, double r) {
  for (size_t w = 0; w < model.planes.size(); ++w) {
    const double at[3] = {state.walls.px[w], state.walls.py[w], state.walls.pz[w]}, x[3] = {c.x(), c.y(), c.z()};
    double normal[3];
    const double d = model.planes[w].distance(at, x, normal);
    if (d < r) return false;
  }
  return true;
}

/// Uniformly distributed orientation (Shoemake 1992, Graphics Gems III).
Quaternion random_orientation(Random& random) {
  const double u1 = random.uniform(), u2 = random.uniform(), u3 = random.uniform();
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1), tau = 2 * std::numbers::pi;
  return {a * std::sin(tau * u2), a * std::cos(tau * u2), b * std::sin(tau * u3), b * std::cos(tau * u3)};
}

/// What one particle to be placed is: a sphere, or a clump template scaled to diameter d.
struct Shape {
  int material;
  int clump;        // -1: sphere
  double diameter;  // [m] sphere diameter, or the clump's volume-equivalent diameter
};

/// Adds the particle at centre c with orientation q (clumps) to the state and the grid.
void add_particle(const Model& model, State& state, PlacementGrid& grid, const Shape& shape, const Vec3& c,
                  const Quaternion& q, const Vec3& velocity, const Vec3& angular_velocity) {
  const double density = model.materials[shape.material].density;
  if (shape.clump < 0) {
    const size_t p = state.add_sphere(c.x(), c.y(), c.z(), 0.5 * shape.diameter, density, shape.material);
    state.vx[p] = velocity.x(), state.vy[p] = velocity.y(), state.vz[p] = velocity.z();
    state.wx[p] = angular_velocity.x(), state.wy[p] = angular_velocity.y(), state.wz[p] = angular_velocity.z();
    grid.add(c, 0.5 * shape.diameter);
    return;
  }
  const ClumpTemplate& t = model.clumps[shape.clump];
  const double d = shape.diameter, d5 = std::pow(d, 5);
  const double mass = density * t.volume * d * d * d;
  const double principal[3] = {density * t.inertia_per_density[0] * d5, density * t.inertia_per_density[1] * d5,
                               density * t.inertia_per_density[2] * d5};
  const double qa[4] = {q.w, q.x, q.y, q.z};
  const size_t b = state.add_body(c.x(), c.y(), c.z(), qa, mass, principal);
  Bodies& bodies = state.bodies;
  bodies.vx[b] = velocity.x(), bodies.vy[b] = velocity.y(), bodies.vz[b] = velocity.z();
  // L = R I R^T w
  const double w[3] = {angular_velocity.x(), angular_velocity.y(), angular_velocity.z()};
  double w_body[3], l_world[3];
  rotate_back(q, w, w_body);
  const double l_body[3] = {principal[0] * w_body[0], principal[1] * w_body[1], principal[2] * w_body[2]};
  rotate(q, l_body, l_world);
  bodies.lx[b] = l_world[0], bodies.ly[b] = l_world[1], bodies.lz[b] = l_world[2];
  for (size_t k = 0; k < t.radii.size(); ++k) {
    const double local[3] = {t.centres[k][0] * d, t.centres[k][1] * d, t.centres[k][2] * d};
    double r[3];
    rotate(q, local, r);
    const Vec3 centre = c + Vec3(r[0], r[1], r[2]);
    const size_t p = state.add_sphere(centre.x(), centre.y(), centre.z(), t.radii[k] * d, density, shape.material);
    state.attach(p, b, local[0], local[1], local[2]);
    // v + w x r
    state.vx[p] = velocity.x() + w[1] * r[2] - w[2] * r[1];
    state.vy[p] = velocity.y() + w[2] * r[0] - w[0] * r[2];
    state.vz[p] = velocity.z() + w[0] * r[1] - w[1] * r[0];
    state.wx[p] = w[0], state.wy[p] = w[1], state.wz[p] = w[2];
    grid.add(centre, t.radii[k] * d);
  }
}

/// Tries random places (and orientations) in the box until the particle overlaps nothing.
bool try_place(const Model& model, State& state, PlacementGrid& grid, Random& random, const Shape& shape, const Vec3& lo,
               const Vec3& hi, const Vec3& velocity, const Vec3& angular_velocity, int attempts) {
  const bool clump = shape.clump >= 0;
  const double reach = clump ? model.clumps[shape.clump].bounding_radius * shape.diameter : 0.5 * shape.diameter;
  const Vec3 size = hi - lo;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    Vec3 c;
    for (int a = 0; a < 3; ++a) {
      const double room = size[a] - 2 * reach;
      c[a] = lo[a] + reach + (room > 0 ? random.uniform() * room : 0.5 * size[a] - reach);
    }
    const Quaternion q = clump ? random_orientation(random) : Quaternion{1, 0, 0, 0};
    bool free = true;
    if (clump) {
      const ClumpTemplate& t = model.clumps[shape.clump];
      for (size_t k = 0; k < t.radii.size() && free; ++k) {
        const double local[3] = {t.centres[k][0] * shape.diameter, t.centres[k][1] * shape.diameter,
                                 t.centres[k][2] * shape.diameter};
        double r[3];
        rotate(q, local, r);
        const Vec3 centre = c + Vec3(r[0], r[1], r[2]);
        const double radius = t.radii[k] * shape.diameter;
        free = grid.free(centre, radius) && clear_of_walls(model, state, centre, radius);
      }
    } else {
      free = grid.free(c, reach) && clear_of_walls(model, state, c, reach);
    }
    if (!free) continue;
    add_particle(model, state, grid, shape, c, q, velocity, angular_velocity);
    return true;
  }
  return false;
}

}  // namespace

State initial_state(const Model& model) {
  State state;
  state.has_meshes = !model.meshes.empty();
  state.mesh_history_width = static_cast<size_t>(model.history_width);
  for (const MeshWall& mesh : model.meshes) {
    TriangleRecords r;
    for (std::vector<double>* c : r.columns()) c->assign(mesh.surface->size(), 0.0);
    state.records.push_back(std::move(r));
  }
  for (const PlaneWall& w : model.planes) {
    state.walls.px.push_back(w.point[0]), state.walls.py.push_back(w.point[1]), state.walls.pz.push_back(w.point[2]);
    state.walls.vx.push_back(w.velocity[0]), state.walls.vy.push_back(w.velocity[1]), state.walls.vz.push_back(w.velocity[2]);
    for (auto* c : {&state.walls.fx, &state.walls.fy, &state.walls.fz}) c->push_back(0.0);
  }
  for (size_t k = 0; k < model.inlets.size(); ++k) {
    InletState in;
    in.random = model.seed ^ (0x9e3779b97f4a7c15ULL * (k + 1));
    in.next_time = model.inlets[k].spec.start;
    state.inlets.push_back(in);
  }
  state.outlets.resize(model.outlets.size());

  Random random(model.seed);
  PlacementGrid grid(std::max(2.0 * model.radius_max, 1e-9));
  constexpr int kAttempts = 2000;
  for (size_t set = 0; set < model.sources.size(); ++set) {
    const ParticleSource& source = model.sources[set];
    const ParticleSetSpec& spec = source.spec;
    const size_t first = state.size();
    if (!spec.positions.empty()) {
      for (const Vec3& c : spec.positions) {
        const Shape shape{source.material, source.clump, draw_diameter(spec.diameter, random)};
        const Quaternion q = source.clump >= 0 ? random_orientation(random) : Quaternion{1, 0, 0, 0};
        add_particle(model, state, grid, shape, c, q, spec.velocity, spec.angular_velocity);
      }
    } else {
      // Random sequential addition, largest first (they are the hardest to fit).
      std::vector<double> diameters(static_cast<size_t>(spec.count));
      for (double& d : diameters) d = draw_diameter(spec.diameter, random);
      std::sort(diameters.begin(), diameters.end(), std::greater<>());
      const Vec3 size = spec.region_max - spec.region_min;
      double solid = 0;
      for (double d : diameters) solid += std::numbers::pi / 6.0 * d * d * d;
      for (size_t k = 0; k < diameters.size(); ++k) {
        const Shape shape{source.material, source.clump, diameters[k]};
        if (!try_place(model, state, grid, random, shape, spec.region_min, spec.region_max, spec.velocity,
                       spec.angular_velocity, kAttempts)) {
          throw CaseError(fmt::format(
              "{}: particles[{}]: placed {} of {} particles; the region holds {:.0f} % solid by volume, and random "
              "placement without overlap stops near 30-35 %. Enlarge the region or lower `count`.",
              spec.location.str(), set, k, diameters.size(), 100.0 * solid / (size.x() * size.y() * size.z())));
        }
      }
    }
    // Glued spheres move with their wall from the start.
    if (source.attached < 0) continue;
    const int w = source.attached;
    for (size_t p = first; p < state.size(); ++p) {
      state.attached[p] = w;
      state.vx[p] = state.walls.vx[w], state.vy[p] = state.walls.vy[w], state.vz[p] = state.walls.vz[w];
      state.wx[p] = state.wy[p] = state.wz[p] = 0.0;
    }
  }
  state.x_built.clear();  // the first step builds the contact lists
  return state;
}

bool inlet_due(const Model& model, const State& state, int k) {
  const Inlet& inlet = model.inlets[k];
  const InletState& st = state.inlets[k];
  if (inlet.spec.count > 0 && st.inserted >= inlet.spec.count) return false;
  return !(state.time < inlet.spec.start || state.time < st.next_time || state.time > inlet.spec.stop);
}

namespace {
double inlet_margin(const Model& model, const Inlet& inlet) {
  return 2.0 * model.radius_max + (inlet.clump >= 0 ? model.clumps[inlet.clump].bounding_radius * inlet.spec.diameter.largest() : 0);
}
}  // namespace

void inlet_reach(const Model& model, int k, double lo[3], double hi[3]) {
  const Inlet& inlet = model.inlets[k];
  const double margin = inlet_margin(model, inlet);
  for (int a = 0; a < 3; ++a) lo[a] = inlet.spec.region_min[a] - margin, hi[a] = inlet.spec.region_max[a] + margin;
}

std::int64_t run_inlet(const Model& model, State& state, int k, const std::vector<std::array<double, 4>>* others) {
  const Inlet& inlet = model.inlets[k];
  InletState& st = state.inlets[k];
  if (!inlet_due(model, state, k)) return 0;
  st.next_time = state.time + inlet.interval;
  // Each batch delivers what is owed by the next insertion, so the flow starts at `start`. Without
  // a mass rate (`count` alone) each batch fills the region: it ends at the first sphere that finds
  // no free place in 5000 random tries (near the random packing limit), which is then no failure.
  const bool fill = inlet.spec.mass_rate <= 0;
  const double owed = fill ? std::numeric_limits<double>::infinity()
                           : inlet.spec.mass_rate * (std::min(st.next_time, inlet.spec.stop) - inlet.spec.start);  // [kg]
  const double density = model.materials[inlet.material].density;
  const double volume_per_d3 = inlet.clump >= 0 ? model.clumps[inlet.clump].volume : std::numbers::pi / 6.0;
  // Spheres near the region, for the overlap checks.
  PlacementGrid grid(std::max(2.0 * model.radius_max, 1e-9));
  const double margin = inlet_margin(model, inlet);
  const Vec3 lo = inlet.spec.region_min.array() - margin, hi = inlet.spec.region_max.array() + margin;
  for (size_t p = 0; p < state.size(); ++p) {
    const Vec3 c(state.x[p], state.y[p], state.z[p]);
    if ((c.array() >= lo.array()).all() && (c.array() <= hi.array()).all()) grid.add(c, state.radius[p]);
  }
  if (others)
    for (const auto& o : *others) grid.add(Vec3(o[0], o[1], o[2]), o[3]);
  Random random(st.random);
  std::int64_t inserted = 0;
  for (;;) {
    if (st.pending_diameter == 0) st.pending_diameter = draw_diameter(inlet.spec.diameter, random);
    const double d = st.pending_diameter;
    const double mass = density * volume_per_d3 * d * d * d;
    if (st.inserted_mass + 0.5 * mass > owed || (inlet.spec.count > 0 && st.inserted >= inlet.spec.count)) break;
    const Shape shape{inlet.material, inlet.clump, d};
    if (!try_place(model, state, grid, random, shape, inlet.spec.region_min, inlet.spec.region_max, inlet.spec.velocity,
                   Vec3::Zero(), fill ? 5000 : 200)) {
      if (!fill) ++st.failed;  // region full: the deficit is carried to the next insertion
      break;
    }
    st.inserted_mass += mass;
    ++st.inserted;
    ++inserted;
    st.pending_diameter = 0;
  }
  st.random = random.state;
  return inserted;
}

void place_body_spheres(const Model& model, State& s, const std::vector<std::int32_t>& body_begin,
                        const std::vector<std::int32_t>& body_members) {
  Bodies& b = s.bodies;
  const long nb = static_cast<long>(b.size());
#pragma omp parallel for schedule(static) if (nb >= kParallelMin)
  for (long k = 0; k < nb; ++k) {
    const Quaternion q{b.qw[k], b.qx[k], b.qy[k], b.qz[k]};
    const double momentum[3] = {b.lx[k], b.ly[k], b.lz[k]}, inverse_inertia[3] = {1.0 / b.ix[k], 1.0 / b.iy[k], 1.0 / b.iz[k]};
    double w[3];
    angular_velocity(q, momentum, inverse_inertia, w);
    for (std::int32_t m = body_begin[k]; m < body_begin[k + 1]; ++m) {
      const std::int32_t p = body_members[m];
      const double local[3] = {s.offset_x[p], s.offset_y[p], s.offset_z[p]};
      double r[3];
      rotate(q, local, r);
      s.x[p] = b.x[k] + r[0], s.y[p] = b.y[k] + r[1], s.z[p] = b.z[k] + r[2];
      s.vx[p] = b.vx[k] + w[1] * r[2] - w[2] * r[1];
      s.vy[p] = b.vy[k] + w[2] * r[0] - w[0] * r[2];
      s.vz[p] = b.vz[k] + w[0] * r[1] - w[1] * r[0];
      s.wx[p] = w[0], s.wy[p] = w[1], s.wz[p] = w[2];
    }
  }
}

}  // namespace dem
