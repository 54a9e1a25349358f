#include "statistics/diagnostics.h"

#include "bodies/rigid_body.h"
#include "core/neighbors.h"
#include "statistics/stream_profile.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace dem {

namespace {

double pair_overlap(const Model& m, const State& s, size_t i, size_t j) {
  double d[3] = {s.x[i] - s.x[j], s.y[i] - s.y[j], s.z[i] - s.z[j]};
  minimum_image(m, d);
  return s.radius[i] + s.radius[j] - std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

double wall_overlap(const Model& m, const State& s, size_t i, size_t w) {
  const double at[3] = {s.walls.px[w], s.walls.py[w], s.walls.pz[w]}, x[3] = {s.x[i], s.y[i], s.z[i]};
  double normal[3];
  return s.radius[i] - m.planes[w].distance(at, x, normal);
}

/// Overlap of particle p's k-th mesh contact at the last evaluation: its radius minus its
/// distance to the contact point; NaN where no evaluation has filled the slot yet (a run's start,
/// a resumed checkpoint).
double mesh_overlap(const State& s, const Workspace& work, size_t p, int k) {
  const size_t c = static_cast<size_t>(s.candidate_begin[p]) + static_cast<size_t>(k);  // results by candidate
  if (c >= work.mesh_slots.cx.size()) return std::numeric_limits<double>::quiet_NaN();
  const double dx = s.x[p] - work.mesh_slots.cx[c], dy = s.y[p] - work.mesh_slots.cy[c], dz = s.z[p] - work.mesh_slots.cz[c];
  return s.radius[p] - std::sqrt(dx * dx + dy * dy + dz * dz);
}

/// Whether every owned particle has its mesh-contact slots (mesh_overlap may be asked).
bool mesh_slots_ready(const State& s) {
  return s.has_meshes && s.candidate_begin.size() >= s.owned() && s.mesh_contacts.count.size() >= s.owned();
}

double body_rotational_energy(const State& s, size_t k) {
  const Bodies& b = s.bodies;
  const double momentum[3] = {b.lx[k], b.ly[k], b.lz[k]};
  double pi[3];
  rotate_back({b.qw[k], b.qx[k], b.qy[k], b.qz[k]}, momentum, pi);
  return 0.5 * (pi[0] * pi[0] / b.ix[k] + pi[1] * pi[1] / b.iy[k] + pi[2] * pi[2] / b.iz[k]);
}

std::uint64_t mix(std::uint64_t h, double v) {
  const auto* p = reinterpret_cast<const unsigned char*>(&v);
  for (size_t k = 0; k < sizeof v; ++k) h = (h ^ p[k]) * 0x100000001b3ULL;
  return h;
}

}  // namespace

/// Plane: Q = sum(m v.n) / h over the particles in a slab of thickness h around the plane (the
/// flux estimator of continuum averaging: each particle crossing spends h / (v.n) in the slab).
/// Box: mass, mass-weighted velocity, centroid offset along `across`, and with bins each bin's
/// mass and momentum along `along`. Clumps count once, at their centre of mass.
namespace {

/// Where each part of the scalars lies in ScalarParts::sums.
struct PartsLayout {
  static constexpr size_t kParticles = 0, kKineticTranslation = 1, kKineticRotation = 2, kContacts = 3, kOverlapSum = 4, kLost = 5,
                          kLostMass = 6, kFixed = 7;
  static constexpr size_t kPerMesh = 7;    // fx, fy, fz, tx, ty, tz, power
  static constexpr size_t kPerSensor = 8;  // flow, count_flow, vx, vy, vz (weighted sums), carried weight, mass, moment
  static constexpr size_t kPerBin = 2;     // mass, momentum along the flow (binned box sensors, after all sensors)
  size_t outlets, meshes, sensors, bins;
  explicit PartsLayout(const Model& model)
      : outlets(model.outlets.size()), meshes(model.meshes.size()), sensors(model.sensors.size()), bins(profile_bin_total(model)) {}
  size_t outlet(size_t k) const { return kFixed + k; }
  size_t mesh(size_t m) const { return kFixed + outlets + kPerMesh * m; }
  size_t sensor(size_t k) const { return kFixed + outlets + kPerMesh * meshes + kPerSensor * k; }
  size_t profiles() const { return sensor(sensors); }
  size_t size() const { return profiles() + kPerBin * bins; }
};

/// The sensors' sums over the owned particles and bodies (PartsLayout::kPerSensor each into
/// `sums`) and, for the binned box sensors, each bin's (PartsLayout::kPerBin into `bin_sums`).
void sum_sensors(const Model& model, const State& s, double* sums, double* bin_sums) {
  if (model.sensors.empty()) return;
  // Each binned sensor's bins and where they begin in bin_sums (a few per row, not per particle).
  std::vector<ProfileBins> bins(model.sensors.size());
  std::vector<size_t> first_bin(model.sensors.size(), 0);
  for (size_t k = 0, next = 0; k < model.sensors.size(); ++k)
    if (has_profile(model.sensors[k])) bins[k] = profile_bins(model.sensors[k]), first_bin[k] = next, next += static_cast<size_t>(bins[k].count);
  auto add = [&](double x, double y, double z, double vx, double vy, double vz, double m) {
    for (size_t k = 0; k < model.sensors.size(); ++k) {
      const SensorSpec& sensor = model.sensors[k];
      if (x < sensor.region_min.x() || x > sensor.region_max.x() || y < sensor.region_min.y() || y > sensor.region_max.y() ||
          z < sensor.region_min.z() || z > sensor.region_max.z())
        continue;
      double* r = sums + PartsLayout::kPerSensor * k;
      if (sensor.kind == SensorSpec::Kind::plane) {
        const Vec3& n = sensor.normal;
        const double distance = (x - sensor.point.x()) * n.x() + (y - sensor.point.y()) * n.y() + (z - sensor.point.z()) * n.z();
        if (std::abs(distance) <= 0.5 * sensor.thickness) {
          const double along = vx * n.x() + vy * n.y() + vz * n.z(), weight = m * std::abs(along);
          r[0] += m * along / sensor.thickness;
          r[1] += along / sensor.thickness;
          r[2] += weight * vx, r[3] += weight * vy, r[4] += weight * vz;
          r[5] += weight;
        }
      } else {
        const Vec3 centre = 0.5 * (sensor.region_min + sensor.region_max);
        const double lateral = (x - centre.x()) * sensor.across.x() + (y - centre.y()) * sensor.across.y() + (z - centre.z()) * sensor.across.z();
        r[6] += m;
        r[2] += m * vx, r[3] += m * vy, r[4] += m * vz;
        r[7] += m * lateral;
        if (bins[k].count > 0) {
          double* bin = bin_sums + PartsLayout::kPerBin * (first_bin[k] + static_cast<size_t>(bins[k].bin(lateral)));
          bin[0] += m;
          bin[1] += m * (vx * sensor.along.x() + vy * sensor.along.y() + vz * sensor.along.z());
        }
      }
    }
  };
  for (size_t p = 0; p < s.owned(); ++p)
    if (s.body[p] < 0) add(s.x[p], s.y[p], s.z[p], s.vx[p], s.vy[p], s.vz[p], 1.0 / s.inv_mass[p]);
  const Bodies& b = s.bodies;
  for (size_t k = 0; k < b.size(); ++k) add(b.x[k], b.y[k], b.z[k], b.vx[k], b.vy[k], b.vz[k], b.mass[k]);
}

}  // namespace

ScalarParts measure_parts(const Model& model, const State& s, const Workspace& work) {
  const PartsLayout at(model);
  ScalarParts out;
  out.sums.assign(at.size(), 0.0);
  double* sums = out.sums.data();
  sums[at.kParticles] = static_cast<double>(s.owned());
  sums[at.kLost] = static_cast<double>(s.lost);
  sums[at.kLostMass] = s.lost_mass;
  double translation = 0, rotation = 0;
  for (size_t p = 0; p < s.owned(); ++p) {
    if (s.body[p] >= 0) continue;  // counted with its body
    const double m = 1.0 / s.inv_mass[p], inertia = 1.0 / s.inv_inertia[p];
    translation += 0.5 * m * (s.vx[p] * s.vx[p] + s.vy[p] * s.vy[p] + s.vz[p] * s.vz[p]);
    rotation += 0.5 * inertia * (s.wx[p] * s.wx[p] + s.wy[p] * s.wy[p] + s.wz[p] * s.wz[p]);
  }
  const Bodies& b = s.bodies;
  for (size_t k = 0; k < b.size(); ++k) {
    translation += 0.5 * b.mass[k] * (b.vx[k] * b.vx[k] + b.vy[k] * b.vy[k] + b.vz[k] * b.vz[k]);
    rotation += body_rotational_energy(s, k);
  }
  sums[at.kKineticTranslation] = translation, sums[at.kKineticRotation] = rotation;
  std::size_t contacts = 0;
  double sum = 0;
  auto count = [&](double overlap, double radius) {
    if (overlap <= 0) return;
    ++contacts;
    sum += overlap / radius;
    out.max_overlap_ratio = std::max(out.max_overlap_ratio, overlap / radius);
  };
  for (size_t k = 0; k < s.pairs.size(); ++k)
    count(pair_overlap(model, s, s.pairs.i[k], s.pairs.j[k]), std::min(s.radius[s.pairs.i[k]], s.radius[s.pairs.j[k]]));
  for (size_t k = 0; k < s.wall_pairs.size(); ++k)
    count(wall_overlap(model, s, s.wall_pairs.i[k], s.wall_pairs.j[k]), s.radius[s.wall_pairs.i[k]]);
  if (mesh_slots_ready(s))  // mesh contacts of the last evaluation
    for (size_t p = 0; p < s.owned(); ++p)
      for (int k = 0; k < s.mesh_contacts.count[p]; ++k)
        if (const double overlap = mesh_overlap(s, work, p, k); std::isfinite(overlap)) count(overlap, s.radius[p]);
  sums[at.kContacts] = static_cast<double>(contacts), sums[at.kOverlapSum] = sum;
  for (size_t k = 0; k < s.outlets.size() && k < at.outlets; ++k) sums[at.outlet(k)] = s.outlets[k].removed_mass;
  const MeshLoads& loads = s.mesh_loads;
  for (size_t m = 0; m < at.meshes && m < loads.fx.size(); ++m) {
    double* l = sums + at.mesh(m);
    for (size_t c = 0; c < 7; ++c) l[c] = loads.mean(m, c);  // over the row's interval
  }
  sum_sensors(model, s, sums + at.sensor(0), sums + at.profiles());
  return out;
}

void add_parts(ScalarParts& total, const ScalarParts& more) {
  if (total.sums.size() < more.sums.size()) total.sums.resize(more.sums.size(), 0.0);
  for (size_t k = 0; k < more.sums.size(); ++k) total.sums[k] += more.sums[k];
  total.max_overlap_ratio = std::max(total.max_overlap_ratio, more.max_overlap_ratio);
}

Scalars finish_scalars(const Model& model, const State& s, const ScalarParts& parts) {
  const PartsLayout at(model);
  if (parts.sums.size() != at.size()) throw std::logic_error("finish_scalars: the parts do not belong to this model");
  const double* sums = parts.sums.data();
  Scalars out;
  out.time = s.time;
  out.step = s.step;
  out.dt = model.dt;
  out.particles = static_cast<std::size_t>(std::llround(sums[at.kParticles]));
  out.lost = std::llround(sums[at.kLost]);
  out.lost_mass = sums[at.kLostMass];
  out.kinetic_translation = sums[at.kKineticTranslation];
  out.kinetic_rotation = sums[at.kKineticRotation];
  out.contacts = static_cast<std::size_t>(std::llround(sums[at.kContacts]));
  out.max_overlap_ratio = parts.max_overlap_ratio;
  out.mean_overlap_ratio = out.contacts ? sums[at.kOverlapSum] / static_cast<double>(out.contacts) : 0.0;
  for (const InletState& in : s.inlets) out.inserted_mass += in.inserted_mass;
  for (size_t k = 0; k < at.outlets; ++k) out.removed_mass += sums[at.outlet(k)], out.outlet_mass.push_back(sums[at.outlet(k)]);
  for (size_t w = 0; w < model.planes.size(); ++w) {
    const auto& n = model.planes[w].normal;
    out.wall_normal_force.push_back(-(s.walls.fx[w] * n[0] + s.walls.fy[w] * n[1] + s.walls.fz[w] * n[2]));
  }
  out.sensors.assign(at.sensors, {});
  for (size_t k = 0; k < at.sensors; ++k) {
    const double* r = sums + at.sensor(k);
    SensorReading& reading = out.sensors[k];
    reading.flow = r[0], reading.count_flow = r[1], reading.vx = r[2], reading.vy = r[3], reading.vz = r[4], reading.mass = r[6];
    const double weight = model.sensors[k].kind == SensorSpec::Kind::plane ? r[5] : r[6];
    if (weight > 0) {
      reading.vx /= weight, reading.vy /= weight, reading.vz /= weight;
      if (model.sensors[k].kind != SensorSpec::Kind::plane) reading.offset = r[7] / weight;
    }
  }
  // The binned box sensors' bins, in the model's order after all sensors.
  for (size_t k = 0, next = 0; k < at.sensors; ++k) {
    if (!has_profile(model.sensors[k])) continue;
    const size_t n = static_cast<size_t>(model.sensors[k].bins);
    const double* b = sums + at.profiles() + PartsLayout::kPerBin * next;
    SensorReading& reading = out.sensors[k];
    reading.bin_mass.resize(n), reading.bin_momentum.resize(n);
    for (size_t j = 0; j < n; ++j) reading.bin_mass[j] = b[PartsLayout::kPerBin * j], reading.bin_momentum[j] = b[PartsLayout::kPerBin * j + 1];
    next += n;
  }
  for (size_t m = 0; m < at.meshes && s.mesh_loads.fx.size() > m; ++m) {
    const double* l = sums + at.mesh(m);
    out.mesh_force.push_back(std::sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]));
    const Eigen::Vector3d w = model.meshes[m].motion.velocity(s.time).angular, torque(l[3], l[4], l[5]);
    out.mesh_torque.push_back(w.norm() > 0 ? torque.dot(w.normalized()) : torque.norm());
    out.mesh_power.push_back(l[6]);
    out.mesh_load.push_back({l[0], l[1], l[2], l[3], l[4], l[5]});
  }
  return out;
}

Scalars measure(const Model& model, const State& s, const Workspace& work) { return finish_scalars(model, s, measure_parts(model, s, work)); }

std::uint64_t state_hash(const State& s, int width) {
  std::vector<size_t> by_id(s.size());
  std::iota(by_id.begin(), by_id.end(), 0);
  std::sort(by_id.begin(), by_id.end(), [&](size_t a, size_t b) { return s.id[a] < s.id[b]; });
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (size_t p : by_id)
    for (double v : {s.x[p], s.y[p], s.z[p], s.vx[p], s.vy[p], s.vz[p], s.wx[p], s.wy[p], s.wz[p]}) h = mix(h, v);
  const Bodies& bodies = s.bodies;
  for (size_t k = 0; k < bodies.size(); ++k)
    for (double v : {bodies.x[k], bodies.y[k], bodies.z[k], bodies.vx[k], bodies.vy[k], bodies.vz[k], bodies.qw[k],
                     bodies.qx[k], bodies.qy[k], bodies.qz[k], bodies.lx[k], bodies.ly[k], bodies.lz[k]})
      h = mix(h, v);
  // Contact histories keyed by (id, id) in sorted order.
  std::vector<std::tuple<std::int64_t, std::int64_t, size_t>> keys;
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    const auto a = s.id[s.pairs.i[k]], b = s.id[s.pairs.j[k]];
    keys.emplace_back(std::min(a, b), std::max(a, b), k);
  }
  std::sort(keys.begin(), keys.end());
  for (const auto& [a, b, k] : keys)
    for (int q = 0; q < width; ++q) h = mix(h, s.pairs.history[k * width + q]);
  return h;
}

void check_numerics(const Model& model, const State& s, const Workspace& work, double max_overlap_ratio) {
  for (size_t p = 0; p < s.size(); ++p) {
    const double values[] = {s.x[p], s.y[p], s.z[p], s.vx[p], s.vy[p], s.vz[p], s.wx[p], s.wy[p], s.wz[p]};
    for (double v : values) {
      if (std::isfinite(v)) continue;
      throw NumericalError(fmt::format(
          "t = {:.6g} s, step {}: particle {} has a non-finite position or velocity (x = [{:g}, {:g}, {:g}]).\n"
          "Likely cause: the time step {:.3g} s is too large for the contact stiffness ({}); use time_step: auto.",
          s.time, s.step, s.id[p], s.x[p], s.y[p], s.z[p], model.dt, model.advice.report));
    }
  }
  for (size_t k = 0; k < s.pairs.size(); ++k) {
    const size_t i = s.pairs.i[k], j = s.pairs.j[k];
    const double ratio = pair_overlap(model, s, i, j) / std::min(s.radius[i], s.radius[j]);
    if (ratio > max_overlap_ratio)
      throw NumericalError(fmt::format(
          "t = {:.6g} s, step {}: particles {} and {} overlap by {:.0f} % of the smaller radius at [{:.4g}, {:.4g}, {:.4g}] m "
          "(limit {:.0f} %).\nLikely causes: a time step too large for the stiffness ({}), or particles inserted into "
          "each other.",
          s.time, s.step, s.id[i], s.id[j], 100 * ratio, s.x[i], s.y[i], s.z[i], 100 * max_overlap_ratio, model.advice.report));
  }
  for (size_t k = 0; k < s.wall_pairs.size(); ++k) {
    const size_t i = s.wall_pairs.i[k];
    const double ratio = wall_overlap(model, s, i, s.wall_pairs.j[k]) / s.radius[i];
    if (ratio > max_overlap_ratio)
      throw NumericalError(fmt::format(
          "t = {:.6g} s, step {}: particle {} overlaps wall '{}' by {:.0f} % of its radius at [{:.4g}, {:.4g}, {:.4g}] m "
          "(limit {:.0f} %).\nLikely causes: a wall stiffness too low for the load, or a time step too large ({}).",
          s.time, s.step, s.id[i], model.planes[s.wall_pairs.j[k]].name, 100 * ratio, s.x[i], s.y[i], s.z[i],
          100 * max_overlap_ratio, model.advice.report));
  }
  // Mesh contacts of the last evaluation, as the records count them. A sphere sunk past the
  // limit into a liner or a belt is on its way through.
  if (!mesh_slots_ready(s)) return;
  for (size_t p = 0; p < s.owned(); ++p)
    for (int k = 0; k < s.mesh_contacts.count[p]; ++k) {
      const double ratio = mesh_overlap(s, work, p, k) / s.radius[p];
      if (!(ratio > max_overlap_ratio)) continue;  // NaN: a slot not yet filled
      const std::int32_t m = s.mesh_contacts.mesh[p * MeshContacts::kSlots + static_cast<size_t>(k)];
      throw NumericalError(fmt::format(
          "t = {:.6g} s, step {}: particle {} overlaps mesh '{}' by {:.0f} % of its radius at [{:.4g}, {:.4g}, {:.4g}] m "
          "(limit {:.0f} %).\nLikely causes: a wall material too soft for the particles' weight and speed (its Young's modulus "
          "sets the contact's stiffness with theirs), or a time step too large ({}).",
          s.time, s.step, s.id[p], m >= 0 && static_cast<size_t>(m) < model.meshes.size() ? model.meshes[m].name : std::string("?"), 100 * ratio,
          s.x[p], s.y[p], s.z[p], 100 * max_overlap_ratio, model.advice.report));
    }
}

double mechanical_energy(const Model& model, const State& s) {
  const double g[3] = {model.gravity[0], model.gravity[1], model.gravity[2]};
  double energy = 0;
  for (size_t p = 0; p < s.owned(); ++p) {
    if (s.body[p] >= 0 || (!s.attached.empty() && s.attached[p] >= 0)) continue;
    const double m = 1.0 / s.inv_mass[p], inertia = 1.0 / s.inv_inertia[p];
    energy += 0.5 * m * (s.vx[p] * s.vx[p] + s.vy[p] * s.vy[p] + s.vz[p] * s.vz[p]);
    energy += 0.5 * inertia * (s.wx[p] * s.wx[p] + s.wy[p] * s.wy[p] + s.wz[p] * s.wz[p]);
    energy -= m * (g[0] * s.x[p] + g[1] * s.y[p] + g[2] * s.z[p]);
  }
  const Bodies& b = s.bodies;
  for (size_t k = 0; k < b.size(); ++k) {
    energy += 0.5 * b.mass[k] * (b.vx[k] * b.vx[k] + b.vy[k] * b.vy[k] + b.vz[k] * b.vz[k]) + body_rotational_energy(s, k);
    energy -= b.mass[k] * (g[0] * b.x[k] + g[1] * b.y[k] + g[2] * b.z[k]);
  }
  return energy;
}

std::string energy_source(const Model& model) {
  if (!model.inlets.empty()) return "inlets insert energy";
  for (const PlaneWall& w : model.planes) {
    if (w.servo) return fmt::format("wall '{}' is servo-controlled", w.name);
    if (w.velocity[0] != 0 || w.velocity[1] != 0 || w.velocity[2] != 0) return fmt::format("wall '{}' moves", w.name);
  }
  for (const MeshWall& m : model.meshes) {
    if (!m.motion.is_static()) return fmt::format("mesh '{}' moves", m.name);
    if (m.surface_velocity.kind != SurfaceVelocitySpec::Kind::none) return fmt::format("mesh '{}' has a moving surface", m.name);
  }
  for (const ActiveEffect& e : model.effects)
    if (e.spec->stage == Stage::adhesion || e.spec->stage == Stage::extra)
      return fmt::format("'{}' attracts particles (surface energy becomes motion)", e.spec->name);
  if (model.has_attached) return "particles are glued to a wall";
  return "";
}

namespace {

/// The energy a source-free run may not gain: each particle's weight over its own diameter
/// (settling, elastic rebound of a packing) plus the initial kinetic energy; at least 1e-12 J.
double energy_scale(const Model& model, const State& s) {
  const double g = std::sqrt(model.gravity[0] * model.gravity[0] + model.gravity[1] * model.gravity[1] +
                             model.gravity[2] * model.gravity[2]);
  double scale = 0;
  for (size_t p = 0; p < s.size(); ++p) {
    const double m = 1.0 / s.inv_mass[p];
    scale += m * g * 2.0 * s.radius[p] + 0.5 * m * (s.vx[p] * s.vx[p] + s.vy[p] * s.vy[p] + s.vz[p] * s.vz[p]);
  }
  return std::max(scale, 1e-12);
}

}  // namespace

EnergyWatch::EnergyWatch(const Model& model, const State& state, double fraction)
    : source_(energy_source(model)), fraction_(fraction) {
  lowest_ = mechanical_energy(model, state);
  scale_ = energy_scale(model, state);
}

void EnergyWatch::check(const Model& model, const State& s) {
  if (active()) check(model, s, mechanical_energy(model, s));
}

void EnergyWatch::check(const Model& model, const State& s, double energy) {
  if (!active()) return;
  if (!std::isfinite(energy)) return;  // check_numerics names the particle
  // Against the energy at the start, not the lowest so far: a contact stores elastic energy
  // (not counted here) and gives it back on rebound.
  if (energy - lowest_ > fraction_ * scale_) {
    size_t fastest = 0;
    double v2 = -1;
    for (size_t p = 0; p < s.owned(); ++p) {
      const double w = s.vx[p] * s.vx[p] + s.vy[p] * s.vy[p] + s.vz[p] * s.vz[p];
      if (w > v2) v2 = w, fastest = p;
    }
    const double rise = energy - lowest_;
    lowest_ = energy;  // report each rise once when the run only warns (numerical_trouble: warn)
    throw NumericalError(fmt::format(
        "t = {:.6g} s, step {}: the energy (kinetic + gravitational) rose by {:.3g} J above its value at the start ({:.0f} % of the energy scale "
        "{:.3g} J, limit {:.0f} %) although nothing in this case supplies energy; the fastest particle is {} at "
        "[{:.4g}, {:.4g}, {:.4g}] m moving at {:.3g} m/s.\nLikely causes: a time step too large against the Rayleigh time "
        "or the contact time ({}); a stiffness too high for the step; particles created overlapping each other or a wall.",
        s.time, s.step, rise, 100 * rise / scale_, scale_, 100 * fraction_, s.size() ? s.id[fastest] : -1,
        s.size() ? s.x[fastest] : 0.0, s.size() ? s.y[fastest] : 0.0, s.size() ? s.z[fastest] : 0.0, std::sqrt(std::max(v2, 0.0)),
        model.advice.report));
  }
}

}  // namespace dem
