// Shared pieces of the virtual tests: set-up reading, the base case, inline meshes, the runner.
#include "lab/virtual_test_support.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numeric>
#include <numbers>

#include "bodies/clump_geometry.h"
#include "case/yaml_check.h"
#include "core/coarse_grain.h"
#include "core/particles.h"
#include "core/step.h"

namespace dem::materials::detail {

namespace {
constexpr double kPi = std::numbers::pi;
}

// ---- set-up reading ----------------------------------------------------------------------

void SetupReader::fail(const std::string& key, const std::string& message) const {
  const std::string experiment = setup_.id.empty() ? "" : fmt::format("experiment '{}': ", setup_.id);
  // A check of what the apparatus holds counts parcels when the tests are coarse-grained.
  const std::string parcels = model_.coarse_grain == 1.0 ? std::string()
                                                         : fmt::format(" (the test runs parcels of coarse_grain {:g}: {:g} x the diameter)",
                                                                       model_.coarse_grain, model_.coarse_grain);
  throw CaseError(fmt::format("{}: {}{}.setup.{}: {}{}", setup_.location.str(), experiment, setup_.test, key, message, parcels));
}

void SetupReader::finish() const {
  std::vector<std::string> given;
  for (const auto& [key, value] : setup_.numbers) given.push_back(key);
  for (const auto& [key, value] : setup_.words) given.push_back(key);
  for (const std::string& key : given) {
    if (std::find(asked_.begin(), asked_.end(), key) != asked_.end()) continue;
    const std::string hint = nearest_word(key, asked_);
    fail(key, fmt::format("not a set-up key of {}{}; valid: {}", setup_.test, hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint),
                          fmt::join(asked_, ", ")));
  }
}

double SetupReader::number(const std::string& key, double min, double max, const std::string& unit) const {
  asked_.push_back(key);
  const auto it = setup_.numbers.find(key);
  if (it == setup_.numbers.end())
    fail(key, fmt::format("missing; the {} test needs it [{}], valid {:g} to {:g}", setup_.test, unit, min, max));
  return number(key, it->second, min, max, unit);
}

double SetupReader::number(const std::string& key, double fallback, double min, double max, const std::string& unit) const {
  if (std::find(asked_.begin(), asked_.end(), key) == asked_.end()) asked_.push_back(key);
  const auto it = setup_.numbers.find(key);
  const double value = it == setup_.numbers.end() ? fallback : it->second;
  if (!(value >= min && value <= max)) fail(key, fmt::format("{:g} {} is out of range; valid {:g} to {:g}", value, unit, min, max));
  return value;
}

std::string SetupReader::word(const std::string& key, const std::string& fallback, const std::vector<std::string>& valid) const {
  asked_.push_back(key);
  const auto it = setup_.words.find(key);
  const std::string value = it == setup_.words.end() ? fallback : it->second;
  if (std::find(valid.begin(), valid.end(), value) == valid.end()) fail(key, fmt::format("'{}' is not valid; valid: {}", value, fmt::join(valid, ", ")));
  return value;
}

std::string SetupReader::wall(const std::string& key, const std::string& fallback_key) const {
  for (const std::string& k : {key, fallback_key})
    if (!k.empty() && std::find(asked_.begin(), asked_.end(), k) == asked_.end()) asked_.push_back(k);
  std::vector<std::string> names;
  for (const MaterialSpec& w : model_.walls) names.push_back(w.name);
  auto it = setup_.words.find(key);
  if (it == setup_.words.end() && !fallback_key.empty()) it = setup_.words.find(fallback_key);
  if (it == setup_.words.end()) {
    if (names.size() == 1) return names[0];
    fail(key, fmt::format("missing: the wall material to use; the material model's walls: {}", names.empty() ? "none" : fmt::format("{}", fmt::join(names, ", "))));
  }
  if (std::find(names.begin(), names.end(), it->second) == names.end())
    fail(key, fmt::format("unknown wall material '{}'; the material model's walls: {}", it->second,
                          names.empty() ? "none" : fmt::format("{}", fmt::join(names, ", "))));
  return it->second;
}

// ---- the base case -----------------------------------------------------------------------

std::string particle_name(const MaterialModel& model) { return model.name.empty() ? "particle" : model.name; }

SizeFigures size_figures(const MaterialModel& model) {
  SizeFigures out;
  Random random(0x5eedULL);
  std::vector<double> d(4000);
  double sum_cube = 0;
  for (double& v : d) v = draw_diameter(model.diameter, random), sum_cube += v * v * v;
  std::sort(d.begin(), d.end());
  double cumulative = 0;
  out.d50 = d.back();
  for (double v : d) {
    cumulative += v * v * v;
    if (cumulative >= 0.5 * sum_cube) {
      out.d50 = v;
      break;
    }
  }
  out.mean_volume = kPi / 6 * sum_cube / static_cast<double>(d.size());
  out.largest = model.diameter.largest();
  // Parcels: every diameter F times the real one (core/coarse_grain.h parcel_diameters).
  const double f = model.coarse_grain;
  out.coarse_grain = f;
  out.d50 *= f, out.largest *= f, out.mean_volume *= f * f * f;
  if (!model.shape.empty()) {
    const ClumpTemplateSpec& t = model.shape[0];
    std::vector<ClumpSphere> spheres;
    for (size_t k = 0; k < t.radii.size(); ++k) spheres.push_back({t.centres[k], t.radii[k]});
    const ClumpMassProperties props = clump_mass_properties(spheres, 1.0);
    const double equivalent = std::cbrt(6.0 * props.volume / kPi);
    double reach = 0;
    for (const ClumpSphere& s : spheres) reach = std::max(reach, (s.centre - props.centre_of_mass).norm() + s.radius);
    out.bounding_factor = 2 * reach / equivalent;
  }
  return out;
}

CaseSpec base_case(const MaterialModel& model, const TestOptions& options, const std::vector<std::string>& walls,
                   const std::string& title) {
  CaseSpec spec;
  spec.path = "<virtual test " + title + ">";
  spec.title = title;
  MaterialSpec particle = model.particle;
  particle.name = particle_name(model);
  spec.materials.push_back(particle);
  std::vector<std::string> used;
  for (const std::string& name : walls) {
    if (std::find(used.begin(), used.end(), name) != used.end()) continue;
    used.push_back(name);
    for (const MaterialSpec& w : model.walls)
      if (w.name == name) spec.materials.push_back(w);
  }
  // Particle-wall pairs of the walls in use; the side that is not a wall is the particle.
  auto is_wall = [&](const std::string& name) { return std::find(used.begin(), used.end(), name) != used.end(); };
  for (InteractionSpec pair : model.wall_pairs) {
    const bool a = is_wall(pair.material_a), b = is_wall(pair.material_b);
    if (a == b) continue;
    (a ? pair.material_b : pair.material_a) = particle.name;
    spec.interactions.push_back(pair);
  }
  spec.contact = model.contact;
  if (!model.shape.empty()) {
    spec.clumps.push_back(model.shape[0]);
    if (spec.clumps[0].name.empty()) spec.clumps[0].name = "shape";
  }
  spec.simulation.seed = options.seed;
  spec.simulation.threads = options.threads;
  spec.simulation.mass_scaling = model.mass_scaling;
  spec.simulation.stiffness_scaling = model.stiffness_scaling;
  spec.simulation.duration = 1e9;  // the tests stop themselves
  spec.simulation.rayleigh_fraction = options.rayleigh_fraction > 0 ? options.rayleigh_fraction : kLabRayleighFraction;
  spec.simulation.steps_per_contact = kLabStepsPerContact;
  spec.output.directory = "";
  return spec;
}

std::int64_t real_count(std::int64_t simulated, double coarse_grain) {
  return std::llround(static_cast<double>(simulated) * coarse_grain * coarse_grain * coarse_grain);
}

std::string coarse_grain_note(double coarse_grain, std::int64_t parcels) {
  const double f = coarse_grain;
  return fmt::format("coarse grain {:g}: {} parcels of {:g} x the real diameter standing for about {:.4g} real particles, the real "
                     "apparatus, the contact parameters scaled by stress similarity (core/coarse_grain.h)",
                     f, parcels, f, static_cast<double>(parcels) * f * f * f);
}

ParticleSetSpec particle_box(const MaterialModel& model, std::int64_t count, const Vec3& lo, const Vec3& hi) {
  ParticleSetSpec set;
  set.material = particle_name(model);
  if (!model.shape.empty()) set.clump = model.shape[0].name.empty() ? "shape" : model.shape[0].name;
  set.diameter = model.diameter;
  set.coarse_grain = model.coarse_grain;
  set.count = real_count(count, model.coarse_grain);
  set.region_min = lo, set.region_max = hi;
  return set;
}

// ---- inline meshes -----------------------------------------------------------------------

int segments_around(double r, double edge) {
  return std::clamp(static_cast<int>(std::ceil(2 * kPi * r / edge)), 48, 256);
}

void Mesh::tube(double r, double z0, double z1, int around, double cell) {
  const int rings = std::max(1, static_cast<int>(std::ceil((z1 - z0) / cell)));
  const auto first = static_cast<std::int32_t>(vertices.size());
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < around; ++j) {
      const double angle = 2 * kPi * j / around;
      vertices.push_back({r * std::cos(angle), r * std::sin(angle), z0 + (z1 - z0) * i / rings});
    }
  auto at = [&](int i, int j) { return first + i * around + (j % around); };
  // (angle, z) right-handed gives an outward normal; swap to face the inside.
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < around; ++j) {
      triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
    }
}

void Mesh::disc(double r, double z, int around, bool up) {
  const auto centre = static_cast<std::int32_t>(vertices.size());
  vertices.push_back({0, 0, z});
  for (int j = 0; j < around; ++j) {
    const double angle = 2 * kPi * j / around;
    vertices.push_back({r * std::cos(angle), r * std::sin(angle), z});
  }
  for (int j = 0; j < around; ++j) {
    const std::int32_t a = centre + 1 + j, b = centre + 1 + (j + 1) % around;
    triangles.push_back(up ? std::array<std::int32_t, 3>{centre, a, b} : std::array<std::int32_t, 3>{centre, b, a});
  }
}

MeshWallSpec Mesh::wall(const std::string& name, const std::string& material) const {
  MeshWallSpec mesh;
  mesh.name = name, mesh.material = material;
  mesh.vertices = vertices, mesh.triangles = triangles;
  return mesh;
}

// ---- running -----------------------------------------------------------------------------

Runner::Runner(const CaseSpec& spec) : model(compile(spec)), state(initial_state(model)) { prepare(model, state, work); }

void Runner::restart(const CaseSpec& spec) {
  model = compile(spec);
  work = Workspace{};
  prepare(model, state, work);
}

void Runner::advance() { step(model, state, work); }

bool Runner::advance_until(const std::function<bool()>& done, double until, double check_every) {
  double next_check = state.time + check_every;
  while (state.time < until) {
    advance();
    if (state.time >= next_check) {
      next_check = state.time + check_every;
      if (done()) return true;
    }
  }
  return done();
}

double Runner::phase_speed(double lowest) const {
  const double g = std::sqrt(model.gravity[0] * model.gravity[0] + model.gravity[1] * model.gravity[1] + model.gravity[2] * model.gravity[2]);
  double most = 0;
  for (std::size_t p = 0; p < state.size(); ++p) {
    const double v2 = state.vx[p] * state.vx[p] + state.vy[p] * state.vy[p] + state.vz[p] * state.vz[p];
    most = std::max(most, v2 + 2 * g * std::max(0.0, state.z[p] - lowest));
  }
  return std::sqrt(most);
}

double Runner::mean_speed(const std::function<bool(std::size_t)>& keep) const {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t p = 0; p < state.size(); ++p) {
    if (keep && !keep(p)) continue;
    sum += std::sqrt(state.vx[p] * state.vx[p] + state.vy[p] * state.vy[p] + state.vz[p] * state.vz[p]);
    ++n;
  }
  return n ? sum / static_cast<double>(n) : 0.0;
}

double mass_of_spheres(const State& state, const std::function<bool(std::size_t)>& counted) {
  std::vector<int> members(state.bodies.size(), 0);
  for (std::size_t p = 0; p < state.size(); ++p)
    if (state.body[p] >= 0) ++members[static_cast<std::size_t>(state.body[p])];
  double m = 0;
  for (std::size_t p = 0; p < state.size(); ++p) {
    if (!counted(p)) continue;
    const std::int32_t b = state.body[p];
    m += b < 0 ? 1.0 / state.inv_mass[p] : state.bodies.mass[static_cast<std::size_t>(b)] / members[static_cast<std::size_t>(b)];
  }
  return m;
}

double Runner::particle_mass() const {
  return mass_of_spheres(state, [](std::size_t) { return true; });
}

std::pair<double, double> fit_line(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k = 0; k < x.size(); ++k) sx += x[k], sy += y[k], sxx += x[k] * x[k], sxy += x[k] * y[k];
  const double den = n * sxx - sx * sx;
  if (x.size() < 2 || den == 0) return {n > 0 ? sy / n : 0.0, 0.0};
  const double b = (n * sxy - sx * sy) / den;
  return {(sy - b * sx) / n, b};
}

double slope_standard_error(const std::vector<double>& x, const std::vector<double>& y, std::pair<double, double> line) {
  const size_t n = x.size();
  if (n < 3) return 0.0;
  const double mean_x = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(n);
  double srr = 0, sxx = 0;
  for (size_t k = 0; k < n; ++k) {
    const double r = y[k] - line.first - line.second * x[k];
    srr += r * r, sxx += (x[k] - mean_x) * (x[k] - mean_x);
  }
  return sxx > 0 ? std::sqrt(srr / static_cast<double>(n - 2) / sxx) : 0.0;
}

void finish(SimulatedOutcome& out, const Runner& run, const Clock& clock, std::int64_t particles, const TestOptions& options) {
  out.particles = particles;
  out.simulated_seconds = run.state.time;
  out.wall_seconds = clock.seconds();
  if (run.model.mass_scaling != 1.0) out.notes.push_back(fmt::format("mass scaling {:g}", run.model.mass_scaling));
  if (run.model.stiffness_scaling != 1.0) out.notes.push_back(fmt::format("stiffness scaling {:g}", run.model.stiffness_scaling));
  if (run.model.coarse_grain != 1.0) {
    out.notes.push_back(coarse_grain_note(run.model.coarse_grain, particles));
    for (const std::string& warning : narrow_openings(run.model)) out.notes.push_back("WARNING: " + warning);
  }
  out.notes.push_back(fmt::format("time step {:.3g} s", run.model.dt));
  if (options.on_final) options.on_final(run.model, run.state);
}

void progress(const TestOptions& options, const std::string& line) {
  if (options.progress) std::cout << line << std::endl;
}

}  // namespace dem::materials::detail
