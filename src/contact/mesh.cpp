#include "contact/mesh.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace dem {

namespace {

inline double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline void sub(const double a[3], const double b[3], double out[3]) {
  out[0] = a[0] - b[0], out[1] = a[1] - b[1], out[2] = a[2] - b[2];
}

}  // namespace

void TriangleSurface::build_topology() {
  const size_t n = triangles.size();
  normals.resize(n);
  areas.resize(n);
  edge_neighbour.assign(n, {-1, -1, -1});
  bounding_radius = 0;
  for (const auto& v : vertices) bounding_radius = std::max(bounding_radius, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
  // Normals and areas.
  for (size_t t = 0; t < n; ++t) {
    const auto& a = vertices[triangles[t][0]];
    const auto& b = vertices[triangles[t][1]];
    const auto& c = vertices[triangles[t][2]];
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double cross[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double length = std::sqrt(dot(cross, cross));
    areas[t] = 0.5 * length;
    normals[t] = length > 0 ? std::array<double, 3>{cross[0] / length, cross[1] / length, cross[2] / length}
                            : std::array<double, 3>{0, 0, 0};
  }
  // Edge neighbours: an edge shared by exactly two triangles links them.
  std::map<std::pair<std::int32_t, std::int32_t>, std::vector<std::pair<std::int32_t, int>>> edges;
  for (size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t u = triangles[t][k], w = triangles[t][(k + 1) % 3];
      edges[{std::min(u, w), std::max(u, w)}].push_back({static_cast<std::int32_t>(t), k});
    }
  for (const auto& [edge, users] : edges) {
    if (users.size() != 2) continue;
    edge_neighbour[users[0].first][users[0].second] = users[1].first;
    edge_neighbour[users[1].first][users[1].second] = users[0].first;
  }
  // Vertex to triangles.
  vertex_begin.assign(vertices.size() + 1, 0);
  for (const auto& tri : triangles)
    for (std::int32_t v : tri) ++vertex_begin[v + 1];
  for (size_t v = 0; v < vertices.size(); ++v) vertex_begin[v + 1] += vertex_begin[v];
  vertex_triangles.resize(3 * n);
  std::vector<std::int32_t> cursor(vertex_begin.begin(), vertex_begin.end() - 1);
  for (size_t t = 0; t < n; ++t)
    for (std::int32_t v : triangles[t]) vertex_triangles[cursor[v]++] = static_cast<std::int32_t>(t);
}

ClosestPoint closest_point_on_triangle(const double p[3], const double a[3], const double b[3], const double c[3]) {
  ClosestPoint out;
  auto finish = [&](const double q[3], Feature f) {
    out.point[0] = q[0], out.point[1] = q[1], out.point[2] = q[2];
    const double d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    out.distance2 = dot(d, d);
    out.feature = f;
    return out;
  };
  double ab[3], ac[3], ap[3];
  sub(b, a, ab), sub(c, a, ac), sub(p, a, ap);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return finish(a, Feature::vertex0);
  double bp[3];
  sub(p, b, bp);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return finish(b, Feature::vertex1);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    const double q[3] = {a[0] + v * ab[0], a[1] + v * ab[1], a[2] + v * ab[2]};
    return finish(q, Feature::edge0);  // edge a-b
  }
  double cp[3];
  sub(p, c, cp);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return finish(c, Feature::vertex2);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    const double q[3] = {a[0] + w * ac[0], a[1] + w * ac[1], a[2] + w * ac[2]};
    return finish(q, Feature::edge2);  // edge c-a
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    const double q[3] = {b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2])};
    return finish(q, Feature::edge1);  // edge b-c
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  const double q[3] = {a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w};
  return finish(q, Feature::face);
}

namespace {

struct QueryData {
  const TriangleSurface* surface;
  double p[3];
  double radius2;
  std::vector<std::int32_t>* out;
};

/// Embree calls this for every triangle whose bounds meet the query sphere; the exact test is ours.
bool query_callback(RTCPointQueryFunctionArguments* args) {
  auto* data = static_cast<QueryData*>(args->userPtr);
  const auto& tri = data->surface->triangles[args->primID];
  const auto& vertices = data->surface->vertices;
  const ClosestPoint cp = closest_point_on_triangle(data->p, vertices[tri[0]].data(), vertices[tri[1]].data(), vertices[tri[2]].data());
  if (cp.distance2 <= data->radius2) data->out->push_back(static_cast<std::int32_t>(args->primID));
  return false;
}

}  // namespace

TriangleBvh::TriangleBvh(const TriangleSurface& surface) : surface_(surface) {
  RTCDevice device = rtcNewDevice("threads=1");
  if (!device) throw std::runtime_error("Embree: cannot create a device");
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), surface.vertices.size()));
  for (size_t v = 0; v < surface.vertices.size(); ++v)
    for (int k = 0; k < 3; ++k) vertices[3 * v + k] = static_cast<float>(surface.vertices[v][k]);
  auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(unsigned), surface.triangles.size()));
  for (size_t t = 0; t < surface.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) indices[3 * t + k] = static_cast<unsigned>(surface.triangles[t][k]);
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  device_ = device;
  scene_ = scene;
}

TriangleBvh::~TriangleBvh() {
  if (scene_) rtcReleaseScene(static_cast<RTCScene>(scene_));
  if (device_) rtcReleaseDevice(static_cast<RTCDevice>(device_));
}

void TriangleBvh::within(const double p[3], double radius, std::vector<std::int32_t>& out) const {
  QueryData data{&surface_, {p[0], p[1], p[2]}, radius * radius, &out};
  RTCPointQuery query;
  query.x = static_cast<float>(p[0]), query.y = static_cast<float>(p[1]), query.z = static_cast<float>(p[2]);
  query.time = 0.0f;
  // Bounds are in float: widen the search a little; the exact test above decides.
  query.radius = static_cast<float>(radius * (1.0 + 1e-5) + 1e-6 * surface_.bounding_radius);
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(static_cast<RTCScene>(scene_), &query, &context, query_callback, &data);
}

}  // namespace dem
