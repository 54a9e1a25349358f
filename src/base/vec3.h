// Small fixed vector for cold code (specs, model set-up). Hot loops use state columns instead.
#pragma once

#include <Eigen/Core>

namespace dem {
using Vec3 = Eigen::Vector3d;
}  // namespace dem
