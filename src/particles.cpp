#include "particles.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
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
  void add(const Vec3& c, double r, size_t index) { cells_[key(c)].push_back(index), centres_.push_back({c, r}); }
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

bool clear_of_walls(const Model& model, const Vec3& c, double r) {
  for (const PlaneWall& w : model.planes) {
    const double d = (c.x() - w.point[0]) * w.normal[0] + (c.y() - w.point[1]) * w.normal[1] + (c.z() - w.point[2]) * w.normal[2];
    if (d < r) return false;
  }
  return true;
}

}  // namespace

State initial_state(const Model& model) {
  State state;
  Random random(model.seed);
  PlacementGrid grid(std::max(2.0 * model.radius_max, 1e-9));
  constexpr int kAttempts = 2000;
  for (size_t set = 0; set < model.sources.size(); ++set) {
    const ParticleSource& source = model.sources[set];
    const ParticleSetSpec& spec = source.spec;
    const double density = model.materials[source.material].density;
    auto place = [&](const Vec3& c, double r) {
      const size_t p = state.add_sphere(c.x(), c.y(), c.z(), r, density, source.material);
      state.vx[p] = spec.velocity.x(), state.vy[p] = spec.velocity.y(), state.vz[p] = spec.velocity.z();
      state.wx[p] = spec.angular_velocity.x(), state.wy[p] = spec.angular_velocity.y(), state.wz[p] = spec.angular_velocity.z();
      grid.add(c, r, p);
    };
    if (!spec.positions.empty()) {
      for (const Vec3& c : spec.positions) place(c, 0.5 * draw_diameter(spec.diameter, random));
      continue;
    }
    // Random sequential addition, largest first (they are the hardest to fit).
    std::vector<double> radii(static_cast<size_t>(spec.count));
    for (double& r : radii) r = 0.5 * draw_diameter(spec.diameter, random);
    std::sort(radii.begin(), radii.end(), std::greater<>());
    const Vec3 size = spec.region_max - spec.region_min;
    double solid = 0;
    for (double r : radii) solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
    for (size_t k = 0; k < radii.size(); ++k) {
      const double r = radii[k];
      bool placed = false;
      for (int attempt = 0; attempt < kAttempts && !placed; ++attempt) {
        Vec3 c;
        for (int a = 0; a < 3; ++a) {
          const double room = size[a] - 2 * r;
          c[a] = spec.region_min[a] + r + (room > 0 ? random.uniform() * room : 0.5 * size[a] - r);
        }
        if (grid.free(c, r) && clear_of_walls(model, c, r)) place(c, r), placed = true;
      }
      if (!placed) {
        throw CaseError(fmt::format(
            "{}: particles[{}]: placed {} of {} particles; the region holds {:.0f} % solid by volume, and random "
            "placement without overlap stops near 30-35 %. Enlarge the region or lower `count`.",
            spec.location.str(), set, k, radii.size(), 100.0 * solid / (size.x() * size.y() * size.z())));
      }
    }
  }
  return state;
}

}  // namespace dem
