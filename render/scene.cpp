// CPU side of a frame: check the input, colour by field, cut away, sort, and choose the depth range.
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "render/internal.h"

namespace dem::render::detail {

namespace {

constexpr std::array<float, 3> nan_grey{0.55f, 0.55f, 0.55f};

void check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("render: " + what);
}

std::uint8_t to_byte(float c) { return std::uint8_t(std::lround(std::clamp(c, 0.0f, 1.0f) * 255)); }

/// Range of a colour map: the one given, or that of the finite data when min or max is NaN.
template <class Values>
std::optional<Range> resolve_range(const std::optional<ColourMap>& map, const Values& value_spans) {
  if (!map) return std::nullopt;
  colour_at(map->name, 0);  // throws for an unknown name
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::span<const float> values : value_spans)
    for (float v : values)
      if (std::isfinite(v)) lo = std::min(lo, double(v)), hi = std::max(hi, double(v));
  Range range{std::isnan(map->min) ? lo : map->min, std::isnan(map->max) ? hi : map->max};
  if (!std::isfinite(range.min) || !std::isfinite(range.max)) range = {0, 1};  // no data at all
  check(range.min <= range.max, "colour map '" + map->label + "' has min > max");
  return range;
}

/// Colour of one value; NaN is grey, a degenerate range maps everything to the middle.
std::array<float, 3> colour_of(const std::string& map, const Range& range, float value) {
  if (std::isnan(value)) return nan_grey;
  const double span = range.max - range.min;
  return colour_at(map, span > 0 ? (value - range.min) / span : 0.5);
}

/// The frame's image size, multisampling and camera are in range (throws std::invalid_argument).
void check_frame(const Frame& frame) {
  check(frame.width >= 1 && frame.height >= 1 && frame.width <= 16384 && frame.height <= 16384,
        "image size must be between 1 and 16384 pixels");
  check(frame.samples == 1 || frame.samples == 2 || frame.samples == 4, "samples must be 1, 2 or 4");
  const Camera& camera = frame.camera;
  check(camera.orthographic ? camera.ortho_height > 0 : camera.fov_deg > 0 && camera.fov_deg < 180,
        "camera needs 0 < fov_deg < 180, or ortho_height > 0");
}

/// Where the camera looks: its view matrix and, in world space, the direction it looks in.
struct View {
  Eigen::Matrix4d view;     // world -> eye
  Eigen::Vector3d forward;  // view direction (eye space -z)
};

View view_of(const Camera& camera) {
  const Eigen::Matrix4d view = view_matrix(camera);  // throws for eye == target
  const Eigen::Vector3d forward = -view.block<1, 3>(2, 0).transpose();
  return {view, forward};
}

/// Colour-map ranges of the particles and of the meshes, from the maps or the data.
void resolve_ranges(const Frame& frame, Scene& scene) {
  std::vector<std::span<const float>> particle_values, mesh_values;
  for (const ParticleLayer& layer : frame.particles) particle_values.push_back(layer.value);
  for (const MeshLayer& layer : frame.meshes) mesh_values.push_back(layer.triangle_value);
  scene.particle_range = resolve_range(frame.particle_colours, particle_values);
  scene.mesh_range = resolve_range(frame.mesh_colours, mesh_values);
}

/// Depth range [near, far] along the view direction, widened by the sphere impostors' quads.
struct DepthRange {
  const Eigen::Vector3d& eye;
  const Eigen::Vector3d& forward;
  double near = std::numeric_limits<double>::infinity();
  double far = -std::numeric_limits<double>::infinity();

  void extend(const Eigen::Vector3d& p, double margin) {
    const double depth = (p - eye).dot(forward);
    near = std::min(near, depth - margin);
    far = std::max(far, depth + margin);
  }
};

/// Spheres: checked, coloured and placed relative to the target, layer by layer.
void add_spheres(const Frame& frame, Scene& scene, DepthRange& depth_range) {
  const Eigen::Vector3d& target = frame.camera.target;
  for (std::size_t l = 0; l < frame.particles.size(); ++l) {
    const ParticleLayer& layer = frame.particles[l];
    const std::size_t n = layer.x.size();
    const std::string name = "particle layer " + std::to_string(l);
    check(layer.y.size() == n && layer.z.size() == n && layer.radius.size() == n,
          name + ": x, y, z and radius differ in length");
    check(layer.value.empty() || layer.value.size() == n, name + ": value length differs from x");
    const bool by_value = scene.particle_range && !layer.value.empty();
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d p(layer.x[i], layer.y[i], layer.z[i]);
      const double r = layer.radius[i];
      if (!p.allFinite() || !(r > 0) || !std::isfinite(r)) continue;  // nothing to draw
      const auto c = by_value ? colour_of(frame.particle_colours->name, *scene.particle_range,
                                          layer.value[i])
                              : layer.colour;
      const Eigen::Vector3f q = (p - target).cast<float>();
      scene.spheres.push_back({q.x(), q.y(), q.z(), float(r), {to_byte(c[0]), to_byte(c[1]), to_byte(c[2]), 255}});
      depth_range.extend(p, 2 * r);  // the quad's corners lie up to ~1.5 r off the centre's depth
    }
  }
}

/// Blended triangles as they come, with the depth of each, waiting to be sorted.
struct BlendedTriangles {
  struct Sortable {
    double depth;
    std::uint32_t first;  // index of its first vertex in `vertices`
  };
  std::vector<Sortable> order;
  std::vector<MeshVertex> vertices;  // 3 per triangle
};

/// Triangles: face normals, cut-away and colour on the CPU so transparent ones can be sorted.
/// Opaque triangles go into the scene, blended ones are returned unsorted.
BlendedTriangles add_triangles(const Frame& frame, const View& view, Scene& scene, DepthRange& depth_range) {
  const Camera& camera = frame.camera;
  const Eigen::Vector3d& eye = camera.eye;
  const Eigen::Vector3d& target = camera.target;
  const Eigen::Vector3d& forward = view.forward;
  BlendedTriangles transparent;
  for (std::size_t l = 0; l < frame.meshes.size(); ++l) {
    const MeshLayer& layer = frame.meshes[l];
    const std::string name = "mesh layer " + std::to_string(l);
    const std::size_t nv = layer.vertices.size(), nt = layer.triangles.size();
    check(layer.triangle_value.empty() || layer.triangle_value.size() == nt,
          name + ": triangle_value length differs from triangles");
    check(layer.opacity >= 0 && layer.opacity <= 1, name + ": opacity must be in [0, 1]");
    if (layer.opacity == 0) continue;
    const bool by_value = scene.mesh_range && !layer.triangle_value.empty();
    const bool blended = layer.opacity < 1;
    for (const auto& v : layer.vertices) depth_range.extend(Eigen::Vector3d(v[0], v[1], v[2]), 0);
    for (std::size_t t = 0; t < nt; ++t) {
      const auto& tri = layer.triangles[t];
      Eigen::Vector3d corner[3];
      for (int k = 0; k < 3; ++k) {
        if (tri[k] < 0 || std::size_t(tri[k]) >= nv)  // message built only on failure: hot loop
          check(false, name + ": triangle " + std::to_string(t) + " indexes a missing vertex");
        const auto& v = layer.vertices[tri[k]];
        corner[k] = {v[0], v[1], v[2]};
      }
      Eigen::Vector3d normal = (corner[1] - corner[0]).cross(corner[2] - corner[0]);
      if (!(normal.norm() > 0)) continue;  // degenerate
      normal.normalize();
      const Eigen::Vector3d centroid = (corner[0] + corner[1] + corner[2]) / 3;
      // Cut-away: drop a triangle whose outward side faces the eye (same test as back-face
      // culling, with front and back swapped). Done here rather than by glCullFace so that
      // blended and opaque triangles of differently flagged layers can share one draw call.
      const Eigen::Vector3d to_triangle = camera.orthographic ? forward : Eigen::Vector3d(centroid - eye);
      if (layer.cutaway && normal.dot(to_triangle) < 0) continue;
      const auto c = by_value ? colour_of(frame.mesh_colours->name, *scene.mesh_range,
                                          layer.triangle_value[t])
                              : layer.colour;
      const std::uint8_t alpha = to_byte(layer.opacity);
      std::vector<MeshVertex>& out = blended ? transparent.vertices : scene.opaque;
      if (blended) transparent.order.push_back({(centroid - eye).dot(forward), std::uint32_t(out.size())});
      const Eigen::Vector3f n = normal.cast<float>();
      for (const Eigen::Vector3d& p : corner) {
        const Eigen::Vector3f q = (p - target).cast<float>();
        out.push_back({q.x(), q.y(), q.z(), n.x(), n.y(), n.z(),
                       {to_byte(c[0]), to_byte(c[1]), to_byte(c[2]), alpha}});
      }
    }
  }
  return transparent;
}

/// Blended triangles far to near (the painter's order; exact except where triangles cross).
void sort_back_to_front(BlendedTriangles& transparent, Scene& scene) {
  using Sortable = BlendedTriangles::Sortable;
  std::vector<Sortable>& order = transparent.order;
  std::sort(order.begin(), order.end(), [](const Sortable& a, const Sortable& b) { return a.depth > b.depth; });
  scene.transparent.reserve(transparent.vertices.size());
  for (const Sortable& s : order)
    scene.transparent.insert(scene.transparent.end(), transparent.vertices.begin() + s.first,
                             transparent.vertices.begin() + s.first + 3);
}

/// View and projection matrices from the depth range, and the image scale at the target.
void set_view_and_projection(const Frame& frame, const View& view, const DepthRange& depth_range, Scene& scene) {
  const Camera& camera = frame.camera;
  const Eigen::Vector3d& eye = camera.eye;
  const Eigen::Vector3d& target = camera.target;
  double near = depth_range.near, far = depth_range.far;
  // Depth range: a perspective near plane must stay in front of the eye; keep the ratio
  // far / near below 1e5 so that a 32-bit float depth buffer resolves the scene.
  const double distance = (target - eye).norm();
  if (!(far >= near)) near = 0.1 * distance, far = 10 * distance;  // empty scene
  // Padding keeps a flat scene (one plane facing the camera) off the clipping planes.
  const double pad = std::max(1e-3 * (far - near), 1e-4 * distance);
  near -= pad, far += pad;
  if (!camera.orthographic) {
    far = std::max(far, 1e-9);
    near = std::max(near, far * 1e-5);
  }
  const double aspect = double(frame.width) / frame.height;
  Eigen::Matrix4d shifted = view.view;  // eye space of points given relative to the target
  shifted.block<3, 1>(0, 3) += view.view.block<3, 3>(0, 0) * target;
  scene.view = shifted.cast<float>();
  scene.projection = projection_matrix(camera, aspect, near, far).cast<float>();
  scene.pixels_per_metre =
      camera.orthographic ? frame.height / camera.ortho_height
                          : frame.height / (2 * distance * std::tan(0.5 * camera.fov_deg * std::numbers::pi / 180));
}

}  // namespace

Scene prepare_scene(const Frame& frame) {
  check_frame(frame);
  Scene scene;
  scene.orthographic = frame.camera.orthographic;
  const View view = view_of(frame.camera);
  resolve_ranges(frame, scene);
  DepthRange depth_range{frame.camera.eye, view.forward};
  add_spheres(frame, scene, depth_range);
  BlendedTriangles transparent = add_triangles(frame, view, scene, depth_range);
  sort_back_to_front(transparent, scene);
  set_view_and_projection(frame, view, depth_range, scene);
  if (frame.cull_hidden) cull_hidden_spheres(scene, frame.width, frame.height);
  return scene;
}

}  // namespace dem::render::detail
