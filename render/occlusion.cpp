// Occlusion culling of spheres on the CPU, so the GPU shades only those that can show.
//
// A sphere impostor writes gl_FragDepth, which turns off llvmpipe's early depth test: every
// fragment of every sphere is shaded, even deep inside a bed where nothing shows. So, front to
// back, each sphere is tested against a half-resolution buffer of conservative depths: it is
// dropped when every buffer pixel its bounding rectangle touches already holds something nearer
// than its nearest point. A kept sphere then writes the deepest depth of its visible cap into the
// pixels lying wholly inside a circle inscribed in its silhouette. Both bounds err towards keeping a sphere,
// so the image is the same as without culling. (Rejected: a depth pre-pass on the GPU, which
// shades every fragment once more; coarse tiles, which no single sphere covers.)
#include <algorithm>
#include <cmath>
#include <limits>

#include "render/internal.h"

namespace dem::render::detail {

void cull_hidden_spheres(Scene& scene, int width, int height) {
  const std::size_t n = scene.spheres.size();
  if (n < 2) return;
  constexpr int shrink = 1;  // buffer pixel = shrink x shrink image pixels
  const int bw = (width + shrink - 1) / shrink, bh = (height + shrink - 1) / shrink;
  const Eigen::Matrix4f& view = scene.view;
  const float sx = scene.projection(0, 0) * 0.5f * width;   // image pixels per unit of x / z
  const float sy = scene.projection(1, 1) * 0.5f * height;

  struct Bound {
    float near_depth, far_depth;  // [m] along the view axis: nearest point, deepest visible point
    float x0, y0, x1, y1;         // bounding rectangle, image pixels (y down)
    float cx, cy, inscribed;      // circle inside the silhouette, image pixels
  };
  std::vector<Bound> bounds(n);
  std::vector<std::uint32_t> order;
  order.reserve(n);
  std::vector<std::uint8_t> keep(n, 1);
  for (std::size_t i = 0; i < n; ++i) {
    const SphereInstance& s = scene.spheres[i];
    const Eigen::Vector3f e = (view * Eigen::Vector4f(s.x, s.y, s.z, 1)).head<3>();
    const float depth = -e.z(), r = s.radius;
    Bound& b = bounds[i];
    b.near_depth = depth - r, b.far_depth = depth + r;
    if (scene.orthographic) {
      b.far_depth = depth + 1e-3f * r;  // the cap facing the viewer lies in front of the centre
      b.cx = 0.5f * width + sx * e.x(), b.cy = 0.5f * height - sy * e.y();
      b.x0 = b.cx - sx * r, b.x1 = b.cx + sx * r, b.y0 = b.cy - sy * r, b.y1 = b.cy + sy * r;
      b.inscribed = std::min(sx, sy) * r;
    } else {
      if (b.near_depth <= 1e-6f * b.far_depth) continue;  // reaches the eye: always drawn
      // What shows of a sphere is the cap facing the eye, within the hemisphere towards it, so
      // it lies no deeper than depth + r sin(angle between view axis and centre direction).
      const float sine = std::sqrt(std::max(0.0f, 1 - depth * depth / e.squaredNorm()));
      b.far_depth = depth + r * std::min(1.0f, sine + 1e-3f);
      // The eye-space cube around the sphere bounds its projection: x / z is extreme at a corner.
      const float xs[2] = {e.x() - r, e.x() + r}, ys[2] = {e.y() - r, e.y() + r};
      const float zs[2] = {b.near_depth, b.far_depth};
      b.x0 = b.y0 = std::numeric_limits<float>::max(), b.x1 = b.y1 = -b.x0;
      for (float x : xs)
        for (float z : zs) b.x0 = std::min(b.x0, x / z), b.x1 = std::max(b.x1, x / z);
      for (float y : ys)
        for (float z : zs) b.y0 = std::min(b.y0, y / z), b.y1 = std::max(b.y1, y / z);
      b.x0 = 0.5f * width + sx * b.x0, b.x1 = 0.5f * width + sx * b.x1;
      const float top = 0.5f * height - sy * b.y1, bottom = 0.5f * height - sy * b.y0;
      b.y0 = top, b.y1 = bottom;
      b.cx = 0.5f * width + sx * e.x() / depth, b.cy = 0.5f * height - sy * e.y() / depth;
      // Around the projected centre the silhouette reaches at least f r / d in every direction.
      b.inscribed = 0.95f * std::min(sx, sy) * r / e.norm();
    }
    if (b.x1 < 0 || b.y1 < 0 || b.x0 > width || b.y0 > height) {
      keep[i] = 0;  // outside the picture
      continue;
    }
    order.push_back(std::uint32_t(i));
  }
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return bounds[a].near_depth < bounds[b].near_depth; });

  std::vector<float> buffer(std::size_t(bw) * bh, std::numeric_limits<float>::infinity());
  const float half_diagonal = 0.7072f * shrink;  // of a buffer pixel, in image pixels
  for (std::uint32_t i : order) {
    const Bound& b = bounds[i];
    const int x0 = std::max(0, int(std::floor(b.x0 / shrink))), x1 = std::min(bw - 1, int(std::floor(b.x1 / shrink)));
    const int y0 = std::max(0, int(std::floor(b.y0 / shrink))), y1 = std::min(bh - 1, int(std::floor(b.y1 / shrink)));
    bool hidden = true;
    for (int y = y0; y <= y1 && hidden; ++y)
      for (int x = x0; x <= x1; ++x)
        if (buffer[std::size_t(y) * bw + x] >= b.near_depth) {
          hidden = false;
          break;
        }
    if (hidden) {
      keep[i] = 0;
      continue;
    }
    // Occlude with the buffer pixels wholly inside the inscribed circle.
    const float reach = b.inscribed - half_diagonal;
    if (reach <= 0) continue;
    const int ox0 = std::max(0, int((b.cx - reach) / shrink)), ox1 = std::min(bw - 1, int((b.cx + reach) / shrink));
    const int oy0 = std::max(0, int((b.cy - reach) / shrink)), oy1 = std::min(bh - 1, int((b.cy + reach) / shrink));
    for (int y = oy0; y <= oy1; ++y)
      for (int x = ox0; x <= ox1; ++x) {
        const float dx = (x + 0.5f) * shrink - b.cx, dy = (y + 0.5f) * shrink - b.cy;
        if (dx * dx + dy * dy <= reach * reach) {
          float& d = buffer[std::size_t(y) * bw + x];
          d = std::min(d, b.far_depth);
        }
      }
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (keep[i]) scene.spheres[kept++] = scene.spheres[i];
  scene.spheres.resize(kept);
}

}  // namespace dem::render::detail
