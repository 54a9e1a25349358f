#include "pages/flow_images.h"

#include <fmt/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <limits>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

#include "render/render.h"

namespace dem::app {

std::string default_camera(const Model& model);

namespace {

/// The case's explicit camera when it gives one (and the command line names no preset), else the
/// preset fitted to the box.
render::Camera camera_for(const Model& model, const ImageOptions& options, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                          double aspect) {
  const OutputSpec& o = model.output;
  if (o.has_camera_pose && options.camera.empty()) {
    render::Camera c;
    c.eye = o.camera_eye, c.target = o.camera_target, c.up = o.camera_up, c.fov_deg = o.camera_fov_deg;
    return c;
  }
  return render::fit_camera(lo, hi, options.camera.empty() ? default_camera(model) : options.camera, aspect);
}

/// The field the particles are coloured by: diameter [mm], material id or speed [m/s].
std::vector<float> particle_values(const State& s, const ImageOptions& options) {
  std::vector<float> value(s.size());
  for (size_t p = 0; p < s.size(); ++p) {
    if (options.colour == "radius") value[p] = static_cast<float>(2000.0 * s.radius[p]);
    else if (options.colour == "material") value[p] = static_cast<float>(s.material[p]);
    else value[p] = static_cast<float>(std::sqrt(s.vx[p] * s.vx[p] + s.vy[p] * s.vy[p] + s.vz[p] * s.vz[p]));
  }
  return value;
}

/// Particles and the field they are coloured by (`value`, which the layer borrows).
void add_particles(const State& s, const std::vector<float>& value, const ImageOptions& options, render::Frame& frame) {
  render::ParticleLayer particles;
  particles.x = s.x, particles.y = s.y, particles.z = s.z, particles.radius = s.radius, particles.value = value;
  frame.particles.push_back(particles);
  render::ColourMap colours;
  colours.label = options.colour == "radius" ? "diameter [mm]" : options.colour == "material" ? "material" : "speed [m/s]";
  if (options.colour == "speed") colours.min = 0.0;
  frame.particle_colours = colours;
}

/// Bounding box [m] of what is drawn, which frames the camera and sizes the walls.
struct Box {
  Eigen::Vector3d lo, hi;
};

/// Mesh m's vertices at its pose at `time`, appended to `placed`, widening the box [lo, hi].
void place_mesh(const Model& model, size_t m, double time, std::vector<std::array<double, 3>>& placed, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
  const Pose pose = model.meshes[m].motion.pose(time);
  for (const auto& v : model.meshes[m].surface->vertices) {
    const Eigen::Vector3d w = pose.rotation * Eigen::Vector3d(v[0], v[1], v[2]) + pose.translation;
    placed.push_back({w.x(), w.y(), w.z()});
    lo = lo.cwiseMin(w), hi = hi.cwiseMax(w);
  }
}

/// Bounding box of what matters: particles and meshes, the meshes placed at their pose now
/// into `placed` (one vertex list per mesh); a 10 cm box at the origin when there is nothing.
Box bounding_box(const Model& model, const State& s, std::vector<std::vector<std::array<double, 3>>>& placed) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t p = 0; p < s.size(); ++p) {
    const Eigen::Vector3d c(s.x[p], s.y[p], s.z[p]);
    lo = lo.cwiseMin(c - Eigen::Vector3d::Constant(s.radius[p])), hi = hi.cwiseMax(c + Eigen::Vector3d::Constant(s.radius[p]));
  }
  // Meshes at their pose now.
  for (size_t m = 0; m < model.meshes.size(); ++m) place_mesh(model, m, s.time, placed[m], lo, hi);
  if (!std::isfinite(lo.x())) lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Constant(0.1);
  return {lo, hi};
}

/// The meshes (`placed`, which the layers borrow) as translucent, cut-away layers.
void add_meshes(const Model& model, const std::vector<std::vector<std::array<double, 3>>>& placed, render::Frame& frame) {
  for (size_t m = 0; m < model.meshes.size(); ++m) {
    render::MeshLayer layer;
    layer.vertices = placed[m];
    layer.triangles = model.meshes[m].surface->triangles;
    layer.cutaway = true;
    layer.opacity = 0.45f;
    frame.meshes.push_back(layer);
  }
}

/// Exact walls as triangles, which the frame's layers borrow.
struct WallShapes {
  // Planes as squares around the particles' extent (an infinite plane cannot be drawn).
  std::vector<std::vector<std::array<double, 3>>> plane_vertices;
  std::vector<std::array<std::int32_t, 3>> quad = {{0, 1, 2}, {0, 2, 3}};
  // Round walls as triangles: the rings of vertices and the triangles between them.
  std::vector<std::vector<std::array<double, 3>>> round_vertices;
  std::vector<std::array<std::int32_t, 3>> round_triangles;
};

/// Steps around a round wall (two vertices each, one per end of the ring).
constexpr int steps_around = 96;

/// A round wall's ring of vertices, two per step around (the ring's two ends), at `at` now.
std::vector<std::array<double, 3>> round_wall_ring(const PlaneWall& wall, const Eigen::Vector3d& n, const Eigen::Vector3d& at,
                                                   const Box& box) {
  // A cylinder over the particles' extent along its axis (an infinite one cannot be drawn);
  // a tube over its length; a disc as its ring.
  const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
  double from = 0, to = wall.length;
  if (wall.shape == PlaneWall::Shape::cylinder) {
    const double a0 = (box.lo - at).dot(n), a1 = (box.hi - at).dot(n);
    from = std::min(a0, a1) - 0.1 * wall.radius, to = std::max(a0, a1) + 0.1 * wall.radius;
  }
  std::vector<std::array<double, 3>> ring;
  for (int k = 0; k < steps_around; ++k) {
    const double angle = 2 * std::numbers::pi * k / steps_around;
    const Eigen::Vector3d radial = std::cos(angle) * u + std::sin(angle) * v;
    const bool disc = wall.shape == PlaneWall::Shape::disc;
    for (int end = 0; end < 2; ++end) {
      const Eigen::Vector3d c = disc ? Eigen::Vector3d(at + (end ? wall.radius : wall.hole) * radial)
                                     : Eigen::Vector3d(at + (end ? to : from) * n + wall.radius * radial);
      ring.push_back({c.x(), c.y(), c.z()});
    }
  }
  return ring;
}

/// The triangles between the two ends of a ring (the same for every round wall).
void add_ring_triangles(std::vector<std::array<std::int32_t, 3>>& round_triangles) {
  for (std::int32_t k = 0; k < steps_around; ++k) {
    const std::int32_t a = 2 * k, b = 2 * ((k + 1) % steps_around);
    round_triangles.push_back({a, b, a + 1}), round_triangles.push_back({b, b + 1, a + 1});
  }
}

/// A plane as a square of half side `half` around the foot of `centre` on it.
std::vector<std::array<double, 3>> plane_square(const Eigen::Vector3d& n, const Eigen::Vector3d& at, const Eigen::Vector3d& centre,
                                                double half) {
  const Eigen::Vector3d foot = centre - (centre - at).dot(n) * n;
  const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
  std::vector<std::array<double, 3>> corners;
  for (auto [a, b] : {std::pair{-1, -1}, std::pair{1, -1}, std::pair{1, 1}, std::pair{-1, 1}}) {
    const Eigen::Vector3d c = foot + half * (a * u + b * v);
    corners.push_back({c.x(), c.y(), c.z()});
  }
  return corners;
}

/// The exact walls at their place now: round walls as rings, planes as squares sized by `box`.
WallShapes wall_shapes(const Model& model, const State& s, const Box& box) {
  WallShapes shapes;
  const Eigen::Vector3d centre = 0.5 * (box.lo + box.hi);
  const double half = 0.6 * (box.hi - box.lo).maxCoeff() + 1e-3;
  for (size_t w = 0; w < model.planes.size(); ++w) {
    const PlaneWall& wall = model.planes[w];
    const Eigen::Vector3d n(wall.normal[0], wall.normal[1], wall.normal[2]);
    const Eigen::Vector3d at(s.walls.px[w], s.walls.py[w], s.walls.pz[w]);
    if (wall.shape != PlaneWall::Shape::plane) {
      std::vector<std::array<double, 3>> ring = round_wall_ring(wall, n, at, box);
      if (shapes.round_triangles.empty()) add_ring_triangles(shapes.round_triangles);
      shapes.round_vertices.push_back(std::move(ring));
      continue;
    }
    shapes.plane_vertices.push_back(plane_square(n, at, centre, half));
  }
  return shapes;
}

/// One wall as a translucent, cut-away layer that borrows `vertices` and `triangles`.
void add_wall(std::span<const std::array<double, 3>> vertices, std::span<const std::array<std::int32_t, 3>> triangles,
              render::Frame& frame) {
  render::MeshLayer layer;
  layer.vertices = vertices;
  layer.triangles = triangles;
  layer.cutaway = true;
  layer.opacity = 0.35f;
  frame.meshes.push_back(std::move(layer));
}

/// Exact walls drawn as translucent, cut-away layers (borrowing `walls`): round ones, then planes.
void add_walls(const WallShapes& walls, render::Frame& frame) {
  for (const auto& ring : walls.round_vertices) add_wall(ring, walls.round_triangles, frame);
  for (const auto& corners : walls.plane_vertices) add_wall(corners, walls.quad, frame);
}

// ---- wall fields: the colour conventions of the pressure and wear maps ---------------------------

/// A per-triangle field as a layer's values (NaN stays NaN: the renderer draws it grey).
std::vector<float> field_values(const std::vector<double>& field) {
  std::vector<float> values;
  values.reserve(field.size());
  for (double v : field) values.push_back(static_cast<float>(v));
  return values;
}

/// The colour map of wall fields (one per mesh drawn), titled `label` with its units: coolwarm
/// from 0 to the 99th percentile of the finite values, so that one hot triangle does not wash
/// out the rest (the peak clamps to the top colour).
render::ColourMap wall_field_colours(std::span<const std::vector<double>> fields, const std::string& label) {
  std::vector<double> all;
  for (const std::vector<double>& field : fields)
    for (double v : field)
      if (std::isfinite(v)) all.push_back(v);
  render::ColourMap colours{"coolwarm", 0.0, 1.0, label};
  if (!all.empty()) {
    std::sort(all.begin(), all.end());
    colours.max = std::max(all[static_cast<size_t>(0.99 * static_cast<double>(all.size() - 1))], 1e-30);
  }
  return colours;
}

// ---- one mesh seen face on -----------------------------------------------------------------------

/// A mesh whose area-weighted mean normal is shorter than this (its unit normals averaged by
/// area) has no face to look at. A flat plate has 1, a 90 degree bend 0.71, a half cylinder
/// 2/pi = 0.64, a hood of equal roof, cheeks and back 0.35 (seen diagonally into it), a
/// cylinder curled through 270 degrees 0.30, one curled through 300 degrees 0.19, a closed box 0.
constexpr double kFaceOnMinimum = 0.25;
/// The share of the image's smaller side the mesh's bounding sphere spans: the rest is a margin
/// for the caption, the colour bar and the scale bar at the corners.
constexpr double kSphereFill = 0.85;

/// [m] A vertex as a vector.
Eigen::Vector3d point(const std::array<double, 3>& v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

/// Up for a camera looking along `forward`: z, or y when it looks nearly straight down or up
/// (as the top preset: x to the right, y up), where z would leave the picture's turn to chance.
Eigen::Vector3d camera_up(const Eigen::Vector3d& forward) {
  return std::abs(forward.z()) > 0.9 ? Eigen::Vector3d(0, 1, 0) : Eigen::Vector3d(0, 0, 1);
}

/// An orthographic camera looking along `forward` at the bounding sphere of `placed` (centred on
/// its box [lo, hi], out to its farthest vertex), which spans kSphereFill of the smaller side.
/// Orthographic so that the scale bar holds over the whole liner (rejected: perspective, whose
/// scale bar holds at the target's depth only, and a curved spoon has many depths).
render::Camera face_on_camera(std::span<const std::array<double, 3>> placed, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                              const Eigen::Vector3d& forward, double aspect) {
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  double radius = 1e-6;  // [m]
  for (const auto& v : placed) radius = std::max(radius, (point(v) - centre).norm());
  render::Camera camera;
  camera.orthographic = true;
  camera.target = centre;
  camera.eye = centre - 2 * radius * forward;  // outside the sphere; the depth range is set per frame
  camera.up = camera_up(forward);
  camera.ortho_height = 2 * radius / (kSphereFill * std::min(1.0, aspect));
  return camera;
}

}  // namespace

void render_state(const Model& model, const State& s, const ImageOptions& options, const std::string& path) {
  render::Frame frame;
  frame.width = options.width, frame.height = options.height;
  // The frame's layers borrow `value`, `placed` and `walls`: they live until the image is written.
  const std::vector<float> value = particle_values(s, options);
  add_particles(s, value, options, frame);
  std::vector<std::vector<std::array<double, 3>>> placed(model.meshes.size());
  const Box box = bounding_box(model, s, placed);
  add_meshes(model, placed, frame);
  const WallShapes walls = wall_shapes(model, s, box);
  add_walls(walls, frame);
  frame.camera = camera_for(model, options, box.lo, box.hi, double(frame.width) / frame.height);
  frame.caption = fmt::format("{}   t = {:.3f} s   {} particles", model.title.empty() ? model.source : model.title, s.time, s.size());
  render::render_png(frame, path);
}

}  // namespace dem::app

namespace dem::app {

std::string default_camera(const Model& model) {
  if (!model.output.render_camera.empty()) return model.output.render_camera;
  return model.equipment_camera.empty() ? "iso" : model.equipment_camera;
}

void render_wall_field(const Model& model, const State& s, const std::vector<std::vector<double>>& field,
                       const std::string& label, const ImageOptions& options, const std::string& path) {
  render::Frame frame;
  frame.width = options.width, frame.height = options.height;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  std::vector<std::vector<std::array<double, 3>>> placed(model.meshes.size());
  std::vector<std::vector<float>> values(model.meshes.size());
  for (size_t m = 0; m < model.meshes.size(); ++m) {
    place_mesh(model, m, s.time, placed[m], lo, hi);
    values[m] = field_values(field[m]);
  }
  if (!std::isfinite(lo.x())) return;
  const render::ColourMap colours = wall_field_colours(field, label);
  for (size_t m = 0; m < model.meshes.size(); ++m) {
    render::MeshLayer layer;
    layer.vertices = placed[m];
    layer.triangles = model.meshes[m].surface->triangles;
    layer.triangle_value = values[m];
    // Walls that carry little of the field (side plates, skirts) are drawn faint and cut away
    // where they face the camera, so they do not hide the hot spots behind them.
    float highest = 0;
    for (float v : values[m])
      if (std::isfinite(v)) highest = std::max(highest, v);
    if (highest < 0.35 * colours.max) layer.opacity = 0.25f, layer.cutaway = true;
    frame.meshes.push_back(layer);
  }
  frame.mesh_colours = colours;
  frame.camera = camera_for(model, options, lo, hi, double(frame.width) / frame.height);
  frame.caption = fmt::format("{}   {}", model.title.empty() ? model.source : model.title, label);
  render::render_png(frame, path);
}

Eigen::Vector3d face_on_direction(std::span<const std::array<double, 3>> vertices,
                                  std::span<const std::array<std::int32_t, 3>> triangles, const Eigen::Vector3d& load) {
  // The area-weighted mean normal: the sum of the triangles' area vectors (twice the area times
  // the unit normal) over the sum of their lengths (rejected: the least axis of the vertices'
  // spread, which is blind to the side the faces look to and to which faces carry area).
  Eigen::Vector3d area_vector(0, 0, 0);
  double area = 0;
  for (const auto& t : triangles) {
    const Eigen::Vector3d a = point(vertices[static_cast<size_t>(t[0])]);
    const Eigen::Vector3d twice = (point(vertices[static_cast<size_t>(t[1])]) - a).cross(point(vertices[static_cast<size_t>(t[2])]) - a);
    area_vector += twice, area += twice.norm();
  }
  const Eigen::Vector3d push = load.allFinite() && load.norm() > 0 ? Eigen::Vector3d(load.normalized()) : Eigen::Vector3d(0, 0, 0);
  if (area > 0 && area_vector.norm() >= kFaceOnMinimum * area) {
    // Face on: looking along the normal sees the back of the faces, against it their front.
    const Eigen::Vector3d normal = area_vector.normalized();
    return normal.dot(push) > 0 ? normal : Eigen::Vector3d(-normal);
  }
  // No face (a spoon curled nearly round, a closed hood): the camera on the particles' side
  // of the mesh, looking along their push, which shows the faces they load; without a push, the
  // iso preset's view, as the map of all meshes.
  if (push.norm() > 0) return push;
  return Eigen::Vector3d(-1, 1, -1).normalized();
}

void render_mesh_field(const Model& model, const State& s, std::size_t mesh, const std::vector<double>& field,
                       const Eigen::Vector3d& load, const std::string& label, const ImageOptions& options, const std::string& path) {
  if (mesh >= model.meshes.size())
    throw std::invalid_argument(fmt::format("{}: mesh {} of a model with {} meshes", path, mesh, model.meshes.size()));
  const MeshWall& wall = model.meshes[mesh];
  // The mesh alone at its pose now; the frame's layer borrows `placed` and `values`.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  std::vector<std::array<double, 3>> placed;
  place_mesh(model, mesh, s.time, placed, lo, hi);
  if (placed.empty()) return;
  const std::vector<float> values = field_values(field);
  render::Frame frame;
  frame.width = options.width, frame.height = options.height;
  render::MeshLayer layer;
  layer.vertices = placed;
  layer.triangles = wall.surface->triangles;
  layer.triangle_value = values;
  frame.meshes.push_back(layer);
  frame.mesh_colours = wall_field_colours(std::span(&field, 1), label);
  // Face on from the particles' side: their push turned from the mesh's frame into the world.
  const Eigen::Vector3d world_load = wall.motion.pose(s.time).rotation * load;
  const Eigen::Vector3d forward = face_on_direction(placed, wall.surface->triangles, world_load);
  frame.camera = face_on_camera(placed, lo, hi, forward, double(frame.width) / frame.height);
  frame.caption = fmt::format("{}   {}", wall.name, label);
  render::render_png(frame, path);
}

}  // namespace dem::app
