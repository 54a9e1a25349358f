// compile(spec): resolve names, switch on effects, mix per-pair parameters, check the time step.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Geometry>

#include "bodies/clump_geometry.h"
#include "case/yaml_check.h"
#include "core/coarse_grain.h"
#include "core/model.h"
#include "core/timestep.h"

namespace dem {

/// Most particles a case may create at the start (a bound on memory, see compile).
constexpr std::int64_t kMaxParticles = 20'000'000;

namespace {

double mix(Mixing rule, double a, double b) {
  switch (rule) {
    case Mixing::arithmetic: return 0.5 * (a + b);
    case Mixing::geometric: return std::sqrt(a * b);
    case Mixing::harmonic: return (a > 0 && b > 0) ? 2.0 * a * b / (a + b) : 0.0;
    case Mixing::minimum: return std::min(a, b);
    case Mixing::maximum: return std::max(a, b);
  }
  return a;
}

/// 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (rigid: E = inf adds nothing).
double effective_youngs(const Material& a, const Material& b) {
  const double inv = (1 - a.poisson_ratio * a.poisson_ratio) / a.youngs_modulus +
                     (1 - b.poisson_ratio * b.poisson_ratio) / b.youngs_modulus;
  return 1.0 / inv;
}

/// 1/G* = 2(2 - nu1)(1 + nu1)/E1 + 2(2 - nu2)(1 + nu2)/E2 (Mindlin; LIGGGHTS/EDEM form).
double effective_shear(const Material& a, const Material& b) {
  const double inv = 2 * (2 - a.poisson_ratio) * (1 + a.poisson_ratio) / a.youngs_modulus +
                     2 * (2 - b.poisson_ratio) * (1 + b.poisson_ratio) / b.youngs_modulus;
  return 1.0 / inv;
}

void add_effect(Model& model, const ContactSpec::Choice& choice, Stage stage, int& param_cursor) {
  if (choice.model == "none") return;
  const EffectSpec* spec = find_effect(stage, choice.model);
  ActiveEffect active{spec, param_cursor, model.history_width, {}};
  for (const auto& option_value : choice.options) {
    // Named copies, not structured bindings: clang 14 (the fuzz build) cannot capture those.
    const std::string& key = option_value.first;
    const std::string& value = option_value.second;
    const auto option = std::find_if(spec->options.begin(), spec->options.end(),
                                     [&](const OptionSpec& o) { return o.key == key; });
    if (option == spec->options.end()) {
      std::string valid = "model";
      for (const auto& o : spec->options) valid += fmt::format(", {}", o.key);
      throw CaseError(fmt::format("{}: contact.{}.{}: unknown option of '{}'; valid: {}", choice.location.str(),
                                  stage_name(stage), key, spec->name, valid));
    }
    const auto at = std::find(option->values.begin(), option->values.end(), value);
    if (at == option->values.end()) {
      std::string valid;
      for (const auto& v : option->values) valid += (valid.empty() ? "" : ", ") + std::string(v);
      throw CaseError(fmt::format("{}: contact.{}.{}: '{}' is not valid; valid: {}", choice.location.str(),
                                  stage_name(stage), key, value, valid));
    }
    active.options[option - spec->options.begin()] = static_cast<std::uint8_t>(at - option->values.begin());
  }
  for (const HistorySpec& h : spec->history) {
    model.history_width += h.width;
    model.history_odd.insert(model.history_odd.end(), h.width, h.odd ? 1 : 0);
  }
  // Every effect of the table at once fits (tests: Effects.AllHistoriesFitABatch); a new effect
  // with history may need kHistoryMax raised.
  if (model.history_width > kHistoryMax)
    throw std::logic_error(fmt::format("contact history of {} doubles exceeds kHistoryMax = {} (src/contact/effect.h)", model.history_width, kHistoryMax));
  param_cursor += static_cast<int>(spec->params.size()) + spec->derived_count;
  model.spin_inputs |= spec->reads_spin;
  model.effects.push_back(active);
}

const ParamSpec* active_param(const Model& model, std::string_view key) {
  for (const ActiveEffect& e : model.effects)
    for (const ParamSpec& p : e.spec->params)
      if (p.key == key) return &p;
  return nullptr;
}

void note_unused(Model& model, const std::map<std::string, double>& params,
                 const std::map<std::string, SourceLocation>& where, const std::string& owner) {
  for (const auto& [key, value] : params) {
    if (active_param(model, key)) continue;
    std::string effect;
    for (const EffectSpec* e : effect_table())
      for (const ParamSpec& p : e->params)
        if (p.key == key && effect.empty()) effect = fmt::format("contact.{}: {}", stage_name(e->stage), e->name);
    model.notes.push_back(fmt::format("{}: {}.{} = {:g} has no effect: it belongs to {}, which this case does not switch on",
                                      where.at(key).str(), owner, key, value, effect));
  }
}

std::uint64_t fnv1a(const void* data, size_t bytes, std::uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t k = 0; k < bytes; ++k) h = (h ^ p[k]) * 0x100000001b3ULL;
  return h;
}

}  // namespace

int Model::material_index(std::string_view name) const {
  for (size_t k = 0; k < materials.size(); ++k)
    if (materials[k].name == name) return static_cast<int>(k);
  return -1;
}

double Model::pair_param(int a, int b, std::string_view key) const {
  for (const ActiveEffect& e : effects)
    for (size_t k = 0; k < e.spec->params.size(); ++k)
      if (e.spec->params[k].key == key) return pair_row(pair_type(a, b))[e.param_offset + k];
  return std::numeric_limits<double>::quiet_NaN();
}

namespace {

// Phases of compile, in the order it calls them. Each builds its part of the Model from the spec;
// the Model built so far is the state they share.

/// Index of a named material, or a CaseError naming the key and the nearest material name.
int material_or_fail(const Model& model, const std::string& name, const SourceLocation& where, const std::string& key) {
  const int index = model.material_index(name);
  if (index >= 0) return index;
  std::vector<std::string> names;
  std::string list;
  for (const auto& m : model.materials) names.push_back(m.name), list += (list.empty() ? "" : ", ") + m.name;
  const std::string hint = nearest_word(name, names);
  throw CaseError(fmt::format("{}: {}: unknown material '{}'{}; materials of this case: {}", where.str(), key, name,
                              hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint), list));
}

/// Index of a named clump template, -1 for none (spheres), or a CaseError naming the nearest template.
int clump_or_fail(const Model& model, const std::string& name, const SourceLocation& where, const std::string& key) {
  if (name.empty()) return -1;
  for (size_t k = 0; k < model.clumps.size(); ++k)
    if (model.clumps[k].name == name) return static_cast<int>(k);
  std::vector<std::string> names;
  for (const auto& known : model.clumps) names.push_back(known.name);
  const std::string hint = nearest_word(name, names);
  throw CaseError(fmt::format("{}: {}: unknown clump template '{}'{}; define it under `clumps:`", where.str(), key, name,
                              hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint)));
}

/// The material's own value of a parameter, or null when it does not state it.
const double* stated_value(const MaterialSpec& m, const ParamSpec& p) {
  const auto it = m.params.find(std::string(p.key));
  return it == m.params.end() ? nullptr : &it->second;
}

/// Largest and smallest sphere a size distribution can create, for a sphere or a clump.
void extend_radii(Model& model, const SizeDistributionSpec& d, int clump) {
  double big = 0.5, small = 0.5;
  if (clump >= 0) {
    const auto& radii = model.clumps[clump].radii;
    big = *std::max_element(radii.begin(), radii.end());
    small = *std::min_element(radii.begin(), radii.end());
  }
  model.radius_max = std::max(model.radius_max, big * d.largest());
  model.radius_min = std::min(model.radius_min, small * d.smallest());
}

void add_materials(const CaseSpec& spec, Model& model) {
  for (const MaterialSpec& m : spec.materials)
    model.materials.push_back({m.name, m.density, m.youngs_modulus, m.poisson_ratio});
  // Mass scaling and reduced stiffness act on the materials particles are made of.
  model.mass_scaling = spec.simulation.mass_scaling;
  model.stiffness_scaling = spec.simulation.stiffness_scaling;
  std::vector<std::uint8_t> particle_material(model.materials.size(), 0);
  for (const auto& p : spec.particles)
    if (const int k = model.material_index(p.material); k >= 0) particle_material[k] = 1;
  for (const auto& in : spec.inlets)
    if (const int k = model.material_index(in.material); k >= 0) particle_material[k] = 1;
  for (size_t k = 0; k < model.materials.size(); ++k) {
    if (!particle_material[k]) continue;
    model.materials[k].density *= model.mass_scaling;
    model.materials[k].youngs_modulus *= model.stiffness_scaling;
    // Parameters fitted at one stiffness need not hold at another: say so when a calibrated
    // material runs at a stiffness more than 25 % away from the one its calibration used.
    if (const auto& record = spec.materials[k].calibration) {
      const double ratio = model.stiffness_scaling / record->stiffness_scaling;
      if (ratio > 1.25 || ratio < 0.8)
        model.notes.push_back(fmt::format(
            "{} was calibrated with its Young's modulus x {:g} ({:.3g} Pa in the virtual tests) and runs here at x {:g} ({:.3g} Pa): "
            "parameters fitted at one stiffness need not hold at another; calibrate at the case's stiffness, or add `bias_check:` "
            "to see what the difference moves",
            spec.materials[k].name, record->stiffness_scaling, spec.materials[k].youngs_modulus * record->stiffness_scaling,
            model.stiffness_scaling, spec.materials[k].youngs_modulus * model.stiffness_scaling));
    }
  }
}

/// Effects in stage order.
void switch_on_effects(const ContactSpec& c, Model& model) {
  int param_cursor = 2;  // columns 0, 1: E*, G*
  if (c.normal.model == "none")
    throw CaseError(fmt::format("{}: contact.normal: a normal force law is required (hertz or linear)", c.normal.location.str()));
  for (const Stage stage : kStages)
    for (const ContactSpec::Choice* choice : c.choices(stage)) add_effect(model, *choice, stage, param_cursor);
  model.pair_stride = param_cursor;
  for (const ActiveEffect& e : model.effects) {
    if (!e.spec->requires_normal.empty() && e.spec->requires_normal != c.normal.model)
      throw CaseError(fmt::format("{}: contact: '{}' is written for the '{}' normal law, but contact.normal is '{}'",
                                  c.normal.location.str(), e.spec->name, e.spec->requires_normal, c.normal.model));
  }
}

/// Pair table: mixed material values, then explicit interactions, then derived values. A
/// material that does not state a parameter leaves the pair's value to the one that does (the
/// particles' rolling resistance or cohesion acts on a wall that says nothing of it, as their
/// own property); neither states it: the default.
void fill_pair_table(const CaseSpec& spec, Model& model) {
  const int n = model.n_materials();
  model.pair_table.assign(static_cast<size_t>(n) * n * model.pair_stride, 0.0);
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      double* row = model.pair_table.data() + static_cast<size_t>(model.pair_type(a, b)) * model.pair_stride;
      row[0] = effective_youngs(model.materials[a], model.materials[b]);
      row[1] = effective_shear(model.materials[a], model.materials[b]);
      for (const ActiveEffect& e : model.effects)
        for (size_t k = 0; k < e.spec->params.size(); ++k) {
          const ParamSpec& p = e.spec->params[k];
          const double *va = stated_value(spec.materials[a], p), *vb = stated_value(spec.materials[b], p);
          row[e.param_offset + k] = va && vb ? mix(p.mixing, *va, *vb) : va ? *va : vb ? *vb : p.default_value;
        }
    }
  }
  for (size_t k = 0; k < spec.interactions.size(); ++k) {
    const InteractionSpec& in = spec.interactions[k];
    const std::string key = fmt::format("interactions[{}].materials", k);
    const int a = material_or_fail(model, in.material_a, in.location, key);
    const int b = material_or_fail(model, in.material_b, in.location, key);
    for (const auto& [name, value] : in.params) {
      for (const ActiveEffect& e : model.effects)
        for (size_t p = 0; p < e.spec->params.size(); ++p)
          if (e.spec->params[p].key == name) {
            model.pair_table[static_cast<size_t>(model.pair_type(a, b)) * model.pair_stride + e.param_offset + p] = value;
            model.pair_table[static_cast<size_t>(model.pair_type(b, a)) * model.pair_stride + e.param_offset + p] = value;
          }
    }
    note_unused(model, in.params, in.where, fmt::format("interactions[{}]", k));
  }
  for (const MaterialSpec& m : spec.materials) note_unused(model, m.params, m.where, "materials." + m.name);
  // Coarse graining scales what the materials and interactions state for real particles; the
  // derived values then follow from the parcels' parameters.
  if (model.coarse_grain != 1.0) scale_pair_parameters(model);
  for (int t = 0; t < n * n; ++t)
    for (const ActiveEffect& e : model.effects)
      if (e.spec->derive) e.spec->derive(model.pair_table.data() + static_cast<size_t>(t) * model.pair_stride + e.param_offset);
}

/// Walls.
void add_plane_walls(const CaseSpec& spec, Model& model) {
  for (size_t k = 0; k < spec.planes.size(); ++k) {
    const PlaneWallSpec& w = spec.planes[k];
    PlaneWall wall{w.name, {w.point.x(), w.point.y(), w.point.z()}, {w.normal.x(), w.normal.y(), w.normal.z()},
                   {w.velocity.x(), w.velocity.y(), w.velocity.z()},
                   material_or_fail(model, w.material, w.location, fmt::format("walls[{}].material", k))};
    wall.shape = w.shape;
    wall.radius = w.radius;
    wall.hole = w.hole_radius;
    wall.length = w.length;
    wall.spin = w.spin;
    wall.servo = w.has_servo;
    wall.target_stress = w.servo.target_stress;
    wall.servo_area = w.servo.area;
    wall.servo_max_speed = w.servo.max_speed;
    model.planes.push_back(wall);
  }
}

/// Mesh walls: triangles inline or from the loader, placed by their transform.
void add_mesh_walls(const CaseSpec& spec, const MeshLoader& loader, Model& model) {
  for (size_t k = 0; k < spec.meshes.size(); ++k) {
    const MeshWallSpec& m = spec.meshes[k];
    auto surface = std::make_shared<TriangleSurface>();
    if (!m.triangles.empty()) {
      const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(m.rotate_deg.z() * std::numbers::pi / 180, Vec3::UnitZ()) *
                                        Eigen::AngleAxisd(m.rotate_deg.y() * std::numbers::pi / 180, Vec3::UnitY()) *
                                        Eigen::AngleAxisd(m.rotate_deg.x() * std::numbers::pi / 180, Vec3::UnitX()))
                                           .toRotationMatrix();
      for (const auto& v : m.vertices) {
        const Vec3 placed = rotation * (Vec3(v[0], v[1], v[2]) * m.unit_scale).cwiseProduct(m.scale) + m.translate;
        surface->vertices.push_back({placed.x(), placed.y(), placed.z()});
      }
      surface->triangles = m.triangles;
    } else {
      if (!loader)
        throw CaseError(fmt::format("{}: meshes[{}].file: reading mesh files needs the geometry library; run the case "
                                    "with the demdesign program", m.location.str(), k));
      TriangleSoup soup = loader(m);
      surface->vertices = std::move(soup.vertices);
      surface->triangles = std::move(soup.triangles);
    }
    if (surface->triangles.empty())
      throw CaseError(fmt::format("{}: meshes[{}]: the mesh has no triangles", m.location.str(), k));
    surface->build_topology();
    MeshWall wall;
    wall.name = m.name;
    wall.material = material_or_fail(model, m.material, m.location, fmt::format("meshes[{}].material", k));
    wall.surface = surface;
    wall.bvh = std::make_shared<TriangleBvh>(*surface);
    wall.motion = m.motion;
    wall.surface_velocity = m.surface;
    wall.active_from = m.active_from;
    model.meshes.push_back(std::move(wall));
  }
}

/// Every entry of `wear.liners` but `default` names a mesh: a misspelt name would leave its mesh
/// on the default liner without a word, and the run's report comes only after the run.
void check_liner_names(const CaseSpec& spec, const Model& model) {
  for (const auto& entry : spec.wear.liners) {
    // Named references, not structured bindings: clang 14 (the fuzz build) cannot capture those.
    const std::string& name = entry.first;
    const LinerSpec& liner = entry.second;
    const auto named = [&name](const MeshWall& m) { return m.name == name; };
    if (name == "default" || std::any_of(model.meshes.begin(), model.meshes.end(), named)) continue;
    std::vector<std::string> names;
    std::string list;
    for (const MeshWall& m : model.meshes) names.push_back(m.name), list += (list.empty() ? "" : ", ") + m.name;
    const std::string hint = nearest_word(name, names);
    throw CaseError(fmt::format("{}: wear.liners.{}: no mesh is named '{}'{}; meshes of this case: {}, or `default`", liner.location.str(),
                                name, name, hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint), list.empty() ? "none" : list));
  }
}

/// The clump templates of a case: its own under `clumps:`, then the shape each library material
/// gives (MaterialSpec::shape), named after the material; a name given twice is refused.
std::vector<ClumpTemplateSpec> clump_templates(const CaseSpec& spec) {
  std::vector<ClumpTemplateSpec> out = spec.clumps;
  for (const MaterialSpec& m : spec.materials) {
    if (!m.shape) continue;
    for (const ClumpTemplateSpec& c : spec.clumps)
      if (c.name == m.name)
        throw CaseError(fmt::format("{}: clumps.{}: the material '{}' gives its particles' shape under that name ({}, `shape:`); "
                                    "rename this template",
                                    c.location.str(), c.name, m.name, m.library_file));
    out.push_back(*m.shape);
    out.back().name = m.name;
  }
  return out;
}

/// The clump a particle set or an inlet uses: the one it names, else its material's shape (a
/// library material's `shape:`, said in the set-up notes), else none (-1, spheres). `clump` is
/// set to the template's name.
int clump_for(const CaseSpec& spec, Model& model, std::string& clump, const std::string& material, const SourceLocation& where,
              const std::string& key) {
  if (clump.empty())
    for (const MaterialSpec& m : spec.materials)
      if (m.name == material && m.shape) {
        clump = m.name;
        model.notes.push_back(fmt::format("{}: clumps of {} spheres, the shape material '{}' gives ({}); `clump:` names another",
                                          key, m.shape->radii.size(), m.name, m.library_file));
      }
  return clump_or_fail(model, clump, where, key + ".clump");
}

/// Clump templates: principal frame, centre of mass at the origin, unit equivalent diameter.
void add_clump_templates(const CaseSpec& spec, Model& model) {
  for (const ClumpTemplateSpec& clump : clump_templates(spec)) {
    std::vector<ClumpSphere> spheres;
    for (size_t k = 0; k < clump.radii.size(); ++k) spheres.push_back({clump.centres[k], clump.radii[k]});
    const ClumpMassProperties props = clump_mass_properties(spheres, 1.0);
    const double scale = 1.0 / std::cbrt(6.0 * props.volume / std::numbers::pi);  // to d_eq = 1 m
    ClumpTemplate t;
    t.name = clump.name;
    for (size_t k = 0; k < spheres.size(); ++k) {
      const Vec3 local = props.principal_axes.transpose() * (spheres[k].centre - props.centre_of_mass) * scale;
      t.centres.push_back({local.x(), local.y(), local.z()});
      t.radii.push_back(spheres[k].radius * scale);
    }
    const double s5 = std::pow(scale, 5);
    t.inertia_per_density = {props.principal_moments.x() * s5, props.principal_moments.y() * s5, props.principal_moments.z() * s5};
    t.volume = props.volume * scale * scale * scale;
    t.bounding_radius = props.bounding_radius * scale;
    model.clumps.push_back(std::move(t));
  }
}

/// Particle sets created at the start, with their material, clump and wall resolved; the radius
/// range starts here.
void add_particle_sources(const CaseSpec& spec, Model& model) {
  model.radius_min = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < spec.particles.size(); ++k) {
    const ParticleSetSpec& p = spec.particles[k];
    const std::string key = fmt::format("particles[{}]", k);
    ParticleSource source{p, material_or_fail(model, p.material, p.location, key + ".material"), -1};
    source.clump = clump_for(spec, model, source.spec.clump, p.material, p.location, key);
    if (model.coarse_grain != 1.0) make_parcels(source.spec, model.coarse_grain);
    extend_radii(model, source.spec.diameter, source.clump);
    // Glued particles: spheres on a plane wall (a rough plate), not clumps, not a cylinder.
    if (!p.attach_to.empty()) {
      for (size_t w = 0; w < model.planes.size(); ++w)
        if (model.planes[w].name == p.attach_to) source.attached = static_cast<int>(w);
      std::vector<std::string> names;
      for (const PlaneWall& w : model.planes) names.push_back(w.name);
      const std::string hint = nearest_word(p.attach_to, names);
      if (source.attached < 0)
        throw CaseError(fmt::format("{}: {}.attach_to: no wall named '{}'{}; particles glue to a plane wall under `walls:`",
                                    p.location.str(), key, p.attach_to,
                                    hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint)));
      if (model.planes[source.attached].shape != PlaneWall::Shape::plane)
        throw CaseError(fmt::format("{}: {}.attach_to: '{}' is not a plane; particles glue only to plane walls",
                                    p.location.str(), key, p.attach_to));
      if (source.clump >= 0)
        throw CaseError(fmt::format("{}: {}.attach_to: glued particles must be spheres ({})", p.location.str(), key,
                                    p.clump.empty() ? fmt::format("material '{}' gives clumps: glue spheres of a material without a `shape:`", p.material)
                                                    : std::string("drop `clump`")));
      model.has_attached = true;
    }
    model.sources.push_back(std::move(source));
  }
}

/// Particle counts are bounded before anything is allocated for them: a mistyped `count`
/// (an extra zero or three) must be an error, not an out-of-memory kill minutes later. The
/// sources' counts and diameters are those of the particles created (parcels, when coarse-grained).
void check_particle_counts(const Model& model) {
  const char* what = model.coarse_grain != 1.0 ? "parcels" : "particles";
  std::int64_t total = 0;
  for (size_t k = 0; k < model.sources.size(); ++k) {
    const ParticleSetSpec& p = model.sources[k].spec;
    total += p.count;
    if (total > kMaxParticles)
      throw CaseError(fmt::format("{}: particles[{}].count: {} {} in all exceeds the limit of {} (about {:.0f} GB at "
                                  "~1 kB per particle with its contacts); lower `count`",
                                  p.location.str(), k, total, what, kMaxParticles, kMaxParticles * 1e3 / 1e9));
    if (!p.positions.empty()) continue;
    // Random placement without overlap stops near 30-35 % solid: refuse what cannot fit
    // before drawing any diameter.
    const double region = (p.region_max - p.region_min).prod();
    const double d = p.diameter.smallest();
    const double scale = p.clump.empty() ? 1.0 : 0.5;  // a clump's spheres may overlap
    const double solid = static_cast<double>(p.count) * std::numbers::pi / 6.0 * d * d * d * scale;
    if (!(solid <= 0.6 * region))
      throw CaseError(fmt::format("{}: particles[{}].count: {} {} of at least {:g} m hold {:.3g} m^3 of solid, "
                                  "{:.0f} % of the region's {:.3g} m^3; random placement stops near 30-35 %. Enlarge "
                                  "`region` or lower `count`",
                                  p.location.str(), k, p.count, what, d, solid, 100.0 * solid / region, region));
  }
}

void add_inlets(const CaseSpec& spec, Model& model) {
  for (size_t k = 0; k < spec.inlets.size(); ++k) {
    const InletSpec& in = spec.inlets[k];
    const std::string key = fmt::format("inlets[{}]", k);
    Inlet inlet{in, material_or_fail(model, in.material, in.location, key + ".material"), -1, in.interval};
    inlet.clump = clump_for(spec, model, inlet.spec.clump, in.material, in.location, key);
    if (model.coarse_grain != 1.0) make_parcels(inlet.spec, model.coarse_grain);
    extend_radii(model, inlet.spec.diameter, inlet.clump);
    model.inlets.push_back(std::move(inlet));
  }
}

void add_outlets(const CaseSpec& spec, Model& model) {
  model.outlets = spec.outlets;
  for (size_t k = 0; k < spec.outlets.size(); ++k) {
    if (!spec.outlets[k].domain) continue;
    if (!spec.simulation.has_domain)
      throw CaseError(fmt::format("{}: outlets[{}].region: `domain` takes what leaves simulation.domain, and the case has none; "
                                  "give simulation.domain {{min: [x,y,z], max: [x,y,z]}}, or a box for the outlet",
                                  spec.outlets[k].location.str(), k));
    if (model.domain_outlet >= 0)
      throw CaseError(fmt::format("{}: outlets[{}].region: `domain` is already the region of outlets[{}] ('{}'); one outlet takes "
                                  "what leaves the domain", spec.outlets[k].location.str(), k, model.domain_outlet,
                                  spec.outlets[model.domain_outlet].name));
    model.domain_outlet = static_cast<int>(k);
  }
}

void check_inlet_ports(const CaseSpec& spec) {
  for (size_t k = 0; k < spec.inlets.size(); ++k)
    if (!spec.inlets[k].port.empty() && !(spec.inlets[k].region_max.array() > spec.inlets[k].region_min.array()).all())
      throw CaseError(fmt::format("{}: inlets[{}].port: '{}' names an equipment port that was not resolved: the "
                                  "case needs `equipment:` with that port (or give `region` instead)",
                                  spec.inlets[k].location.str(), k, spec.inlets[k].port));
}

/// A stream profile's bins (SensorSpec::bins) of a sensor a generator or a test built: the case
/// reader checks those of a file, with their lines.
void check_sensor_bins(const SensorSpec& sensor, size_t k) {
  if (sensor.bins == 0) return;
  std::string wrong;
  if (sensor.kind != SensorSpec::Kind::box) wrong = "a plane sensor has no bins";
  else if (sensor.bins < 0 || sensor.bins > kMostSensorBins) wrong = fmt::format("{} is out of range; valid: [0, {}]", sensor.bins, kMostSensorBins);
  else if (sensor.along.norm() < 1e-12) wrong = "need a flow direction `along`, which is zero";
  if (!wrong.empty()) throw CaseError(fmt::format("{}: sensors[{}].bins: {} (sensor '{}')", sensor.location.str(), k, wrong, sensor.name));
}

/// Sensors: unit directions, a slab a couple of particles thick, unique names, bins only in boxes.
void add_sensors(const CaseSpec& spec, Model& model) {
  for (size_t k = 0; k < spec.sensors.size(); ++k) {
    SensorSpec sensor = spec.sensors[k];
    for (size_t j = 0; j < k; ++j)
      if (spec.sensors[j].name == sensor.name)
        throw CaseError(fmt::format("{}: sensors[{}].name: '{}' is used twice; sensor names must differ", sensor.location.str(), k, sensor.name));
    check_sensor_bins(sensor, k);
    sensor.normal.normalize();
    sensor.across.normalize();
    if (sensor.along.norm() > 0) sensor.along.normalize();
    if (sensor.kind == SensorSpec::Kind::plane && sensor.thickness <= 0) sensor.thickness = 4.0 * model.radius_max;
    model.sensors.push_back(sensor);
  }
}

/// Options.
void set_options(const CaseSpec& spec, Model& model) {
  const SimulationSpec& s = spec.simulation;
  model.duration = s.duration;
  model.gravity = {s.gravity.x(), s.gravity.y(), s.gravity.z()};
  model.seed = s.seed;
  model.stop_on_trouble = s.stop_on_trouble;
  model.max_overlap_ratio = s.max_overlap_ratio;
  model.energy_rise_limit = s.energy_rise_limit;
  model.threads = s.threads;
  model.skin = s.skin > 0 ? s.skin : 0.5 * model.radius_min;
  model.has_domain = s.has_domain;
  model.domain_min = {s.domain_min.x(), s.domain_min.y(), s.domain_min.z()};
  model.domain_max = {s.domain_max.x(), s.domain_max.y(), s.domain_max.z()};
  model.output = spec.output;
  for (int a = 0; a < 3; ++a)
    if (s.periodic[a]) model.period[a] = s.domain_max[a] - s.domain_min[a];
}

/// Largest gap at which any effect acts, over every material pair.
void find_interaction_range(Model& model) {
  const int n = model.n_materials();
  for (const ActiveEffect& e : model.effects) {
    if (!e.spec->range) continue;
    for (int t = 0; t < n * n; ++t) {
      const double* row = model.pair_row(t);
      model.interaction_range = std::max(model.interaction_range, e.spec->range(row, row + e.param_offset, model.radius_max));
    }
  }
}

void choose_time_step(const CaseSpec& spec, Model& model) {
  const SimulationSpec& s = spec.simulation;
  model.advice = advise_time_step(model, s);
  model.dt = model.advice.dt;
  if (!model.advice.safe && s.refuse_unsafe_step)
    throw CaseError(fmt::format("{}: simulation.time_step: {:g} s is unsafe for this material and particle size:\n{}\n"
                                "Use a smaller step, `time_step: auto`, or `unsafe_time_step: warn` to run anyway.",
                                spec.path, model.dt, model.advice.report));
  if (!model.advice.safe) model.notes.push_back("time step is unsafe (unsafe_time_step: warn):\n" + model.advice.report);
}

/// Inlets insert in batches: often enough that a batch is a thin layer of the region.
void set_inlet_intervals(Model& model, double g_norm) {
  for (Inlet& inlet : model.inlets) {
    if (inlet.interval > 0) continue;
    const Vec3 extent = inlet.spec.region_max - inlet.spec.region_min;
    const double speed = inlet.spec.velocity.norm();
    const double clear = speed > 0 ? 0.25 * extent.maxCoeff() / speed
                                   : (g_norm > 0 ? 0.25 * std::sqrt(2.0 * extent.maxCoeff() / g_norm) : 0.01);
    inlet.interval = std::clamp(clear, 20.0 * model.dt, 0.05);
  }
}

/// What an inlet's region can deliver: particles placed at random without overlaps fill a box to
/// about 30 % solid (random sequential placement jams near 38 %), and the box empties in the time
/// the particles take to cross it along their velocity, from their inlet speed with the part of
/// gravity along it (a belt port: length / belt speed, as the generators size them; from rest:
/// the fall through the box). A rate beyond 40 % solid cannot be delivered (the inlet falls
/// behind and its particles crowd the box); beyond 30 % it is a note.
void check_inlet_rates(Model& model, double g_norm) {
  for (const Inlet& inlet : model.inlets) {
    if (inlet.spec.mass_rate <= 0) continue;
    const Vec3 extent = inlet.spec.region_max - inlet.spec.region_min;
    const double speed = inlet.spec.velocity.norm();
    const Vec3 gravity(model.gravity[0], model.gravity[1], model.gravity[2]);
    const Vec3 direction = speed > 0 ? Vec3(inlet.spec.velocity / speed) : (g_norm > 0 ? Vec3(gravity / g_norm) : Vec3(0, 0, -1));
    const double along = extent.cwiseProduct(direction.cwiseAbs()).sum();  // [m] the box's depth along the motion
    const double g_along = std::max(0.0, gravity.dot(direction));         // [m/s^2]
    const double empties = g_along > 0 ? (std::sqrt(speed * speed + 2.0 * g_along * along) - speed) / g_along
                                       : (speed > 0 ? along / speed : 0.0);  // [s]
    if (!(empties > 0)) continue;
    const double carried = extent.prod() * model.materials[inlet.material].density / empties;  // [kg/s] at 100 % solid
    const double solid = inlet.spec.mass_rate / carried;
    const std::string what = fmt::format(
        "inlets.{}: {:.4g} t/h needs its region ({}{:.3g} x {:.3g} x {:.3g} m, emptied every {:.3g} s {}) {:.0f} % solid", inlet.spec.name,
        inlet.spec.mass_rate * 3.6, inlet.spec.port.empty() ? "" : fmt::format("the port '{}', ", inlet.spec.port), extent.x(), extent.y(),
        extent.z(), empties, speed > 0 ? fmt::format("at {:.3g} m/s", speed) : "by gravity", 100 * solid);
    const std::string remedy = inlet.spec.port.empty()
                                   ? "a larger region or a higher inlet velocity, or a lower mass rate"
                                   : "a longer or faster feed (the equipment's feed length, width or speed), or a lower mass rate";
    if (solid > 0.40)
      throw CaseError(fmt::format("{}: {}; particles placed at random without overlaps reach about 30 %, never 40 %: the inlet "
                                  "cannot deliver it. Use {}",
                                  inlet.spec.location.str(), what, remedy));
    if (solid > 0.30)
      model.notes.push_back(fmt::format("{}; random placement reaches about 30 %: the inlet may fall behind its rate (its "
                                        "failed insertions are counted at the end of the run). {} would leave room",
                                        what, remedy));
  }
}

/// Servo walls: area from the periodic cross-section, speed limit from the step.
void size_servo_walls(const CaseSpec& spec, Model& model) {
  for (size_t k = 0; k < model.planes.size(); ++k) {
    PlaneWall& w = model.planes[k];
    if (!w.servo) continue;
    if (w.servo_area <= 0) {
      double area = 1.0;
      int axes = 0;
      for (int a = 0; a < 3; ++a)
        if (std::abs(w.normal[a]) < 1e-12 && model.period[a] > 0) area *= model.period[a], ++axes;
      if (axes != 2)
        throw CaseError(fmt::format("{}: walls[{}].servo.area: needed unless the wall's normal is an axis and the two "
                                    "other axes are periodic", spec.planes[k].location.str(), k));
      w.servo_area = area;
    }
    if (w.servo_max_speed <= 0) w.servo_max_speed = 0.002 * model.radius_min / model.dt;
  }
}

/// Periodic axes: the minimum image is unique only if a period spans three cells.
void check_periodic_lengths(const CaseSpec& spec, const Model& model) {
  const double cell = 2.0 * model.radius_max + model.interaction_range + model.skin;
  for (int a = 0; a < 3; ++a)
    if (model.period[a] > 0 && model.period[a] < 3.0 * cell)
      throw CaseError(fmt::format("{}: simulation.domain: the periodic length along {} is {:g} m; it must be at least "
                                  "three neighbour cells, {:g} m (2 x largest radius + interaction range + skin, x 3)",
                                  spec.path, "xyz"[a], model.period[a], 3.0 * cell));
}

/// Hash of what determines the physics (checkpoints refuse a different model).
std::uint64_t physics_hash(const Model& model) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  h = fnv1a(model.pair_table.data(), model.pair_table.size() * sizeof(double), h);
  for (const ActiveEffect& e : model.effects) h = fnv1a(e.spec->name.data(), e.spec->name.size(), h);
  h = fnv1a(&model.dt, sizeof model.dt, h);
  h = fnv1a(model.gravity.data(), sizeof model.gravity, h);
  for (const PlaneWall& w : model.planes) {
    h = fnv1a(w.point.data(), sizeof w.point, h);
    h = fnv1a(w.normal.data(), sizeof w.normal, h);
    // (What older versions hashed stays as it was, so their checkpoints still resume.)
    if (w.shape == PlaneWall::Shape::disc || w.shape == PlaneWall::Shape::tube) {
      const double shape[4] = {static_cast<double>(w.shape), w.radius, w.hole, w.length};
      h = fnv1a(shape, sizeof shape, h);
    }
    if (w.spin != 0) h = fnv1a(&w.spin, sizeof w.spin, h);
  }
  // Parcels of another size with the same pair table (a Hertz law without cohesion) are another model.
  if (model.coarse_grain != 1.0) h = fnv1a(&model.coarse_grain, sizeof model.coarse_grain, h);
  return h;
}

}  // namespace

Model compile(const CaseSpec& spec, const MeshLoader& loader) {
  Model model;
  model.source = spec.path;
  model.title = spec.title;

  // Contact law: materials, effects, per-pair parameters (scaled for parcels, core/coarse_grain.h).
  add_materials(spec, model);
  model.coarse_grain = case_coarse_grain(spec);
  for (std::string& note : calibration_coarse_grain_notes(spec, model.coarse_grain)) model.notes.push_back(std::move(note));
  switch_on_effects(spec.contact, model);
  fill_pair_table(spec, model);

  // Walls, clump templates, particles and what enters, leaves and measures them.
  add_plane_walls(spec, model);
  add_mesh_walls(spec, loader, model);
  check_liner_names(spec, model);
  add_clump_templates(spec, model);
  add_particle_sources(spec, model);
  check_particle_counts(model);
  const double g_norm = std::sqrt(spec.simulation.gravity.squaredNorm());  // [m/s^2]
  add_inlets(spec, model);
  add_outlets(spec, model);
  check_inlet_ports(spec);
  add_sensors(spec, model);
  model.design = spec.design;
  model.equipment_camera = spec.equipment_camera;

  // Options, the time step, and what depends on it.
  set_options(spec, model);
  find_interaction_range(model);
  choose_time_step(spec, model);
  set_inlet_intervals(model, g_norm);
  check_inlet_rates(model, g_norm);
  size_servo_walls(spec, model);
  check_periodic_lengths(spec, model);
  if (model.coarse_grain != 1.0) model.coarse_grain_report = describe_coarse_grain(spec, model);

  model.hash = physics_hash(model);
  return model;
}

std::string describe_effects() {
  std::string out;
  for (const EffectSpec* e : effect_table()) {
    out += fmt::format("contact.{}: {}\n    {}\n    source: {}\n", stage_name(e->stage), e->name,
                       e->summary, e->citation);
    for (const ParamSpec& p : e->params) {
      // How coarse graining scales it (core/coarse_grain.h): said when it changes or is unknown.
      const std::string parcels = !p.coarse_grain_exponent         ? std::string(", coarse_grain refused (no scaling declared)")
                                  : *p.coarse_grain_exponent != 0 ? fmt::format(", x F^{} for parcels", *p.coarse_grain_exponent)
                                                                  : std::string();
      out += fmt::format("    {:<26} [{}] default {:g}, range [{:g}, {:g}]{}{}: {}\n", p.key, p.unit, p.default_value,
                         p.min_value, p.max_value, p.tunable ? ", tunable" : "", parcels, p.doc);
    }
    for (const OptionSpec& o : e->options) {
      std::string values;
      for (const auto& v : o.values) values += (values.empty() ? "" : " | ") + std::string(v);
      out += fmt::format("    option {}: {} (default {}): {}\n", o.key, values, o.values[0], o.doc);
    }
    for (const HistorySpec& hs : e->history) out += fmt::format("    history: {} ({} values)\n", hs.name, hs.width);
    if (const CandidateSpec* c = e->candidate) {
      std::string fitted, moves;
      for (const FittedParam& f : c->fitted)
        fitted += fmt::format("{}{} from {:g} in [{:g}, {:g}]{}", fitted.empty() ? "" : ", ", f.key, f.start, f.min, f.max,
                              c->scale ? " (x the material's scale)" : "");
      for (const std::string_view m : c->moves) moves += (moves.empty() ? "" : ", ") + std::string(m);
      out += fmt::format("    diagnosis candidate ({}): fits {}\n      signature: {}\n      moves: {}\n", c->title, fitted,
                         c->signature, moves);
    }
  }
  return out;
}

}  // namespace dem
