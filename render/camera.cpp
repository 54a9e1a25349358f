// Camera matrices and automatic framing of a bounding box.
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "render/internal.h"

namespace dem::render {

namespace {

struct Basis {
  Eigen::Vector3d right, up, forward;  // forward: from the eye towards the target
};

Basis camera_basis(const Eigen::Vector3d& forward_in, const Eigen::Vector3d& up_in) {
  Basis basis;
  basis.forward = forward_in.normalized();
  Eigen::Vector3d right = basis.forward.cross(up_in);
  // An up vector along the view direction: fall back to whichever axis is most perpendicular.
  if (right.norm() < 1e-9 * up_in.norm() || up_in.norm() == 0) {
    Eigen::Index axis;
    basis.forward.cwiseAbs().minCoeff(&axis);
    right = basis.forward.cross(Eigen::Vector3d::Unit(axis));
  }
  basis.right = right.normalized();
  basis.up = basis.right.cross(basis.forward);
  return basis;
}

}  // namespace

namespace detail {

Eigen::Matrix4d view_matrix(const Camera& camera) {
  const Eigen::Vector3d forward = camera.target - camera.eye;
  if (!(forward.norm() > 0) || !forward.allFinite())
    throw std::invalid_argument("render: camera eye and target coincide or are not finite");
  const Basis basis = camera_basis(forward, camera.up);
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.block<1, 3>(0, 0) = basis.right.transpose();
  view.block<1, 3>(1, 0) = basis.up.transpose();
  view.block<1, 3>(2, 0) = -basis.forward.transpose();
  view.block<3, 1>(0, 3) = -view.block<3, 3>(0, 0) * camera.eye;
  return view;
}

Eigen::Matrix4d projection_matrix(const Camera& camera, double aspect, double near, double far) {
  Eigen::Matrix4d projection = Eigen::Matrix4d::Zero();
  if (camera.orthographic) {
    // glOrtho with a symmetric view volume.
    const double top = 0.5 * camera.ortho_height, right = aspect * top;
    projection(0, 0) = 1 / right;
    projection(1, 1) = 1 / top;
    projection(2, 2) = -2 / (far - near);
    projection(2, 3) = -(far + near) / (far - near);
    projection(3, 3) = 1;
  } else {
    // gluPerspective.
    const double focal = 1 / std::tan(0.5 * camera.fov_deg * std::numbers::pi / 180);
    projection(0, 0) = focal / aspect;
    projection(1, 1) = focal;
    projection(2, 2) = (far + near) / (near - far);
    projection(2, 3) = 2 * far * near / (near - far);
    projection(3, 2) = -1;
  }
  return projection;
}

}  // namespace detail

Camera fit_camera(const Eigen::Vector3d& bbox_min, const Eigen::Vector3d& bbox_max,
                  const std::string& preset, double aspect, bool orthographic) {
  if (!bbox_min.allFinite() || !bbox_max.allFinite() || (bbox_max - bbox_min).minCoeff() < 0)
    throw std::invalid_argument("render: fit_camera needs a finite box with min <= max");
  if (!(aspect > 0)) throw std::invalid_argument("render: fit_camera needs aspect > 0");
  Eigen::Vector3d forward, up{0, 0, 1};
  if (preset == "side") forward = {0, 1, 0};
  else if (preset == "front") forward = {-1, 0, 0};
  else if (preset == "top") forward = {0, 0, -1}, up = {0, 1, 0};
  else if (preset == "iso") forward = Eigen::Vector3d(-1, 1, -1).normalized();
  else throw std::invalid_argument("render: unknown camera preset '" + preset +
                                   "' (side, front, top, iso)");

  Camera camera;
  camera.up = up;
  camera.orthographic = orthographic;
  const Eigen::Vector3d centre = 0.5 * (bbox_min + bbox_max);
  const double half_diagonal = std::max(0.5 * (bbox_max - bbox_min).norm(), 1e-6);
  const Basis basis = camera_basis(forward, up);
  constexpr double fill = 0.92;  // the box spans 92 % of the limiting image dimension

  // Box corners in camera axes relative to the centre: (right, up, depth along forward).
  double needed_half_height = 0, needed_distance = 0;
  const double tan_y = std::tan(0.5 * camera.fov_deg * std::numbers::pi / 180) * fill;
  const double tan_x = tan_y * aspect;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p(corner & 1 ? bbox_max.x() : bbox_min.x(),
                            corner & 2 ? bbox_max.y() : bbox_min.y(),
                            corner & 4 ? bbox_max.z() : bbox_min.z());
    const Eigen::Vector3d d = p - centre;
    const double a = std::abs(d.dot(basis.right)), b = std::abs(d.dot(basis.up));
    const double depth = d.dot(basis.forward);
    needed_half_height = std::max({needed_half_height, b / fill, a / (aspect * fill)});
    // Perspective: the corner at depth (distance + depth) must satisfy |a| <= that * tan_x.
    needed_distance = std::max({needed_distance, a / tan_x - depth, b / tan_y - depth});
  }
  camera.target = centre;
  if (orthographic) {
    camera.ortho_height = std::max(2 * needed_half_height, 1e-6);
    camera.eye = centre - 2 * half_diagonal * basis.forward;  // depth range is set per frame
  } else {
    camera.eye = centre - std::max(needed_distance, 1.01 * half_diagonal) * basis.forward;
  }
  return camera;
}

}  // namespace dem::render
