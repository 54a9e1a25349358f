// Triangle surfaces as walls: topology for exact contact resolution, the closest feature of a
// triangle to a point, and an Embree BVH that finds the triangles near a point.
//
// Contact resolution (one physical contact counted once): every candidate triangle gives its
// closest point to the sphere centre and the feature it lies on (face, edge or vertex). A face
// contact always counts. An edge or vertex contact is dropped when a triangle that shares that
// edge or vertex is strictly closer (the sphere is then over that triangle, and the feature is
// not the surface's closest point there), and contacts whose points coincide are merged. So a
// sphere rolling across the shared edge of coplanar triangles, or sitting on a vertex shared by
// six, feels exactly the analytic plane; a convex ridge gives one edge contact; a concave
// corner gives one face contact per face it touches.
// Rejected alternative: edge/vertex "normal cone" tests, which need per-edge convexity and are
// fragile on nearly coplanar CAD triangles; the distance comparison needs no angle tolerance.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace dem {

/// A triangulated surface in its own frame, with the adjacency contact resolution needs.
struct TriangleSurface {
  std::vector<std::array<double, 3>> vertices;         // [m] local frame
  std::vector<std::array<std::int32_t, 3>> triangles;  // vertex indices
  std::vector<std::array<double, 3>> normals;          // unit, right-hand rule
  std::vector<double> areas;                           // [m^2]
  /// Triangle across edge k (vertices k, k+1); -1 on a boundary or a non-manifold edge.
  std::vector<std::array<std::int32_t, 3>> edge_neighbour;
  /// Triangles around each vertex: vertex_triangles[vertex_begin[v] .. vertex_begin[v+1]).
  std::vector<std::int32_t> vertex_begin, vertex_triangles;
  double bounding_radius = 0;  ///< [m] largest distance of a vertex from the local origin

  /// Builds normals, areas and adjacency from vertices and triangles.
  void build_topology();
  std::size_t size() const { return triangles.size(); }
};

/// Which part of a triangle a closest point lies on.
enum class Feature : std::uint8_t { face, edge0, edge1, edge2, vertex0, vertex1, vertex2 };

struct ClosestPoint {
  double point[3];   // [m]
  double distance2;  // [m^2] squared distance to the query point
  Feature feature;
};

/// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5).
ClosestPoint closest_point_on_triangle(const double p[3], const double a[3], const double b[3], const double c[3]);

/// Embree BVH over one surface's triangles (in its local frame). Queries are thread-safe.
class TriangleBvh {
 public:
  explicit TriangleBvh(const TriangleSurface& surface);
  ~TriangleBvh();
  TriangleBvh(const TriangleBvh&) = delete;
  TriangleBvh& operator=(const TriangleBvh&) = delete;
  /// Appends to `out` every triangle within `radius` [m] of `p` (exact distance test).
  void within(const double p[3], double radius, std::vector<std::int32_t>& out) const;

 private:
  const TriangleSurface& surface_;
  void* device_ = nullptr;  // RTCDevice
  void* scene_ = nullptr;   // RTCScene
};

}  // namespace dem
