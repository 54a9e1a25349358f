// Shared by the render library's own files; not part of the public interface.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <vector>

#include "render/render.h"

namespace dem::render::detail {

/// One sphere as the GPU reads it, centre relative to the camera target.  // 20 bytes
struct SphereInstance {
  float x, y, z, radius;  // [m]
  std::uint8_t rgba[4];
};

/// One corner of a triangle; three per triangle, flat face normal.  // 28 bytes
struct MeshVertex {
  float x, y, z;     // [m] relative to the camera target
  float nx, ny, nz;  // unit face normal (counter-clockwise winding)
  std::uint8_t rgba[4];
};

struct Range {
  double min, max;
};

/// What the OpenGL side draws, prepared on the CPU: validated, coloured, culled and sorted.
struct Scene {
  std::vector<SphereInstance> spheres;
  std::vector<MeshVertex> opaque;       // 3 per triangle
  std::vector<MeshVertex> transparent;  // 3 per triangle, back to front
  Eigen::Matrix4f view;        // world relative to the target -> eye space (camera looks down -z)
  Eigen::Matrix4f projection;  // eye space -> clip space
  bool orthographic = false;
  double pixels_per_metre = 0;  // image scale at the target's depth
  std::optional<Range> particle_range, mesh_range;  // colour-map ranges in force
};

/// Checks the frame (throws std::invalid_argument) and builds the arrays the GPU draws.
Scene prepare_scene(const Frame& frame);

/// Drops the spheres that nearer spheres hide, and those outside the picture (occlusion.cpp).
void cull_hidden_spheres(Scene& scene, int width, int height);

/// Camera matrices (OpenGL conventions: right-handed eye space, clip depth in [-1, 1]).
Eigen::Matrix4d view_matrix(const Camera& camera);  // world -> eye
Eigen::Matrix4d projection_matrix(const Camera& camera, double aspect, double near, double far);

/// Caption, colour bars and scale bar, drawn onto the finished image with FreeType.
void draw_overlays(const Frame& frame, const Scene& scene, Image& image);

}  // namespace dem::render::detail
