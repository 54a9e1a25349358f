// Clump mass properties: closed forms for disjoint spheres, the lens formula for overlapping
// pairs, independent 1-D integrals over the axis of axisymmetric unions, inclusion-exclusion for a
// tetrahedron without triple overlaps, and symmetry / rotation invariance where no closed form is
// at hand. Tolerances are stated per check: 1e-12 on exact paths, 1e-9 on integrated results
// (measured <= 6e-12 at the default resolution).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "bodies/clump_geometry.h"

namespace dem {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;

double sphere_volume(double r) { return 4.0 / 3.0 * kPi * r * r * r; }
double rel_diff(double a, double b) { return std::abs(a - b) / std::abs(b); }
double rel_diff(const Matrix3d& a, const Matrix3d& b) { return (a - b).norm() / b.norm(); }
double rel_diff(const Vector3d& a, const Vector3d& b) { return (a - b).norm() / b.norm(); }

/// Volume [m^3] common to spheres r1, r2 [m] at centre distance d [m], |r1 - r2| < d < r1 + r2.
double lens_volume(double r1, double r2, double d) {
  const double g = r1 + r2 - d;
  return kPi * g * g * (d * d + 2 * d * r2 - 3 * r2 * r2 + 2 * d * r1 + 6 * r1 * r2 - 3 * r1 * r1) / (12 * d);
}

/// Sphere on an axis: position s [m] along the axis, radius r [m].
struct AxialSphere {
  double s, r;
};

/// Integrals along the axis of a body of revolution with cross-section radius a(s):
/// int pi a^2, int pi a^2 s, int pi/2 a^4 (axial moment / density), int pi a^2 (a^2/4 + s^2)
/// (moment about the perpendicular axis through s = 0, / density).
struct AxialIntegrals {
  double volume, first, i_axis, i_perp0;
};

/// a^2 = max over the spheres (union) or min (lens) of r^2 - (s - s_i)^2. a^2 is one quadratic
/// between the kinks (sphere ends, radical planes), so the integrands are polynomials of degree
/// <= 4 there and composite Simpson with 4000 intervals per piece is accurate to ~1e-14.
AxialIntegrals axial_integrals(const std::vector<AxialSphere>& spheres, bool lens = false) {
  std::vector<double> breaks;
  for (const AxialSphere& a : spheres) {
    breaks.insert(breaks.end(), {a.s - a.r, a.s + a.r});
    for (const AxialSphere& b : spheres)
      if (b.s > a.s) breaks.push_back(a.s + ((b.s - a.s) * (b.s - a.s) + a.r * a.r - b.r * b.r) / (2 * (b.s - a.s)));
  }
  std::sort(breaks.begin(), breaks.end());
  auto a2 = [&](double s) {
    double v = lens ? 1e300 : 0.0;
    for (const AxialSphere& a : spheres) {
      const double q = a.r * a.r - (s - a.s) * (s - a.s);
      v = lens ? std::min(v, q) : std::max(v, q);
    }
    return std::max(v, 0.0);
  };
  AxialIntegrals m{0, 0, 0, 0};
  const int n = 4000;
  for (std::size_t k = 0; k + 1 < breaks.size(); ++k) {
    const double h = (breaks[k + 1] - breaks[k]) / n;
    for (int i = 0; i <= n; ++i) {
      const double s = breaks[k] + i * h, q = a2(s);
      const double w = h / 3 * (i == 0 || i == n ? 1 : (i % 2 ? 4 : 2));
      m.volume += w * kPi * q;
      m.first += w * kPi * q * s;
      m.i_axis += w * kPi / 2 * q * q;
      m.i_perp0 += w * kPi * q * (q / 4 + s * s);
    }
  }
  return m;
}

/// Expected properties of an axisymmetric body whose axis s runs along unit u from `origin`.
struct Expected {
  double volume;
  Vector3d com;
  Matrix3d inertia;
};
Expected place_axial(const AxialIntegrals& m, double density, const Vector3d& origin, const Vector3d& u) {
  const double s_com = m.first / m.volume;
  const double i_axis = density * m.i_axis;
  const double i_perp = density * m.i_perp0 - density * m.volume * s_com * s_com;
  const Matrix3d uu = u * u.transpose();
  return {m.volume, origin + s_com * u, i_axis * uu + i_perp * (Matrix3d::Identity() - uu)};
}

std::vector<ClumpSphere> on_axis(const std::vector<AxialSphere>& spheres, const Vector3d& origin, const Vector3d& u) {
  std::vector<ClumpSphere> out;
  for (const AxialSphere& a : spheres) out.push_back({origin + a.s * u, a.r});
  return out;
}

TEST(ClumpGeometry, SingleSphereIsExact) {
  const double r = 0.05, rho = 2500;  // [m], [kg/m^3]
  const std::vector<ClumpSphere> one = {{Vector3d(0.3, -1.2, 2.0), r}};
  const ClumpMassProperties p = clump_mass_properties(one, rho);
  const double v = sphere_volume(r), i = 0.4 * rho * v * r * r;
  EXPECT_LT(rel_diff(p.volume, v), 1e-12);
  EXPECT_LT(rel_diff(p.mass, rho * v), 1e-12);
  EXPECT_LT((p.centre_of_mass - one[0].centre).norm(), 1e-12 * r);
  EXPECT_LT(rel_diff(p.inertia, i * Matrix3d::Identity()), 1e-12);
  for (int k = 0; k < 3; ++k) EXPECT_LT(rel_diff(p.principal_moments[k], i), 1e-12);
  EXPECT_LT(rel_diff(p.bounding_radius, r), 1e-12);
}

TEST(ClumpGeometry, TouchingDumbbellIsExact) {
  const double r = 0.01, rho = 1000;
  const std::vector<ClumpSphere> pair = {{Vector3d(-r, 0, 0), r}, {Vector3d(r, 0, 0), r}};
  const ClumpMassProperties p = clump_mass_properties(pair, rho);
  const double m = rho * sphere_volume(r), own = 0.4 * m * r * r;
  EXPECT_LT(rel_diff(p.volume, 2 * sphere_volume(r)), 1e-12);
  EXPECT_LT(p.centre_of_mass.norm(), 1e-12 * r);
  const double iyy = 2 * (own + m * r * r);
  EXPECT_LT(rel_diff(p.inertia, Vector3d(2 * own, iyy, iyy).asDiagonal().toDenseMatrix()), 1e-12);
  EXPECT_LT(rel_diff(p.bounding_radius, 2 * r), 1e-12);
}

TEST(ClumpGeometry, TouchingThreeSphereLineIsExact) {
  const double r = 0.004, rho = 2650;
  const Vector3d o(1, 2, 3);
  const std::vector<ClumpSphere> line = {{o + Vector3d(-2 * r, 0, 0), r}, {o, r}, {o + Vector3d(2 * r, 0, 0), r}};
  const ClumpMassProperties p = clump_mass_properties(line, rho);
  const double m = rho * sphere_volume(r), own = 0.4 * m * r * r;
  const double iyy = 3 * own + 2 * m * (2 * r) * (2 * r);
  EXPECT_LT(rel_diff(p.volume, 3 * sphere_volume(r)), 1e-12);
  EXPECT_LT((p.centre_of_mass - o).norm(), 1e-12 * r);
  EXPECT_LT(rel_diff(p.inertia, Vector3d(3 * own, iyy, iyy).asDiagonal().toDenseMatrix()), 1e-12);
  EXPECT_LT(rel_diff(p.principal_moments, Vector3d(3 * own, iyy, iyy)), 1e-12);
}

// Overlapping pairs: r1, r2, centre distance d (in units of r = 2 mm) along direction u.
struct PairCase {
  double r1, r2, d;
  Vector3d u;
};

TEST(ClumpGeometry, OverlappingPairsMatchLensFormulaAndAxialIntegral) {
  const double r = 0.002, rho = 2650;
  const Vector3d origin(0.01, -0.02, 0.005);
  const std::vector<PairCase> cases = {
      {1, 1, 1.0, Vector3d(0, 0, 1)},    {1, 1, 1.0, Vector3d(1, 2, 3)},     {1, 1, 1.5, Vector3d(1, 0, 0)},
      {1, 1, 1.5, Vector3d(-3, 7, 2)},   {1, 0.6, 1.1, Vector3d(5, -4, 9)},  {1, 0.6, 0.5, Vector3d(0, 1, 0)},
      {0.7, 1, 1.2, Vector3d(1, 1, 1)},  {1, 1, 1.999999, Vector3d(2, -1, 1)},
  };
  for (const PairCase& c : cases) {
    SCOPED_TRACE(testing::Message() << "r1 " << c.r1 << " r2 " << c.r2 << " d " << c.d << " u " << c.u.transpose());
    const Vector3d u = c.u.normalized();
    const std::vector<AxialSphere> axial = {{0, c.r1 * r}, {c.d * r, c.r2 * r}};
    const ClumpMassProperties p = clump_mass_properties(on_axis(axial, origin, u), rho);
    const Expected e = place_axial(axial_integrals(axial), rho, origin, u);
    const double v_union =
        sphere_volume(c.r1 * r) + sphere_volume(c.r2 * r) - lens_volume(c.r1 * r, c.r2 * r, c.d * r);
    // The two references agree (Simpson exact up to rounding on each polynomial piece).
    EXPECT_LT(rel_diff(e.volume, v_union), 1e-12);
    // Tolerance 1e-9 relative (measured <= 6e-12 at the default resolution; needed: well below 1e-3).
    EXPECT_LT(rel_diff(p.volume, v_union), 1e-9);
    EXPECT_LT(rel_diff(p.mass, rho * v_union), 1e-9);
    EXPECT_LT((p.centre_of_mass - e.com).norm(), 1e-9 * r);
    EXPECT_LT(rel_diff(p.inertia, e.inertia), 1e-9);
    // Axis of revolution carries the unique (smallest) moment for these shapes.
    EXPECT_GT(std::abs(p.principal_axes.col(0).dot(u)), 1 - 1e-9);
  }
}

TEST(ClumpGeometry, ErrorStaysBelowRequestedResolution) {
  const std::vector<AxialSphere> axial = {{0, 1.0}, {1.1, 0.6}, {2.0, 0.8}};
  const Vector3d u = Vector3d(0.3, -0.5, 0.8).normalized();
  const Expected e = place_axial(axial_integrals(axial), 1.0, Vector3d::Zero(), u);
  for (int res = 3; res <= 11; ++res) {
    const ClumpMassProperties p = clump_mass_properties(on_axis(axial, Vector3d::Zero(), u), 1.0, res);
    // Documented contract: ~10^-res relative (plus a 1e-13 rounding floor).
    const double bound = std::pow(10.0, -res) + 1e-13;
    EXPECT_LT(rel_diff(p.volume, e.volume), bound) << "resolution " << res;
    EXPECT_LT(rel_diff(p.inertia, e.inertia), bound) << "resolution " << res;
  }
}

/// Regular tetrahedron of spheres radius r, edge e, centred on the origin.
std::vector<ClumpSphere> tetrahedron(double r, double e) {
  const double k = e / (2 * std::sqrt(2.0));
  return {{k * Vector3d(1, 1, 1), r}, {k * Vector3d(1, -1, -1), r},
          {k * Vector3d(-1, 1, -1), r}, {k * Vector3d(-1, -1, 1), r}};
}

TEST(ClumpGeometry, TetrahedronPairwiseOverlapMatchesInclusionExclusion) {
  // e = 1.9 r: every pair overlaps, but the face circumradius e/sqrt(3) > r, so no point lies in
  // three spheres and union = sum of spheres - sum of the six lenses, exactly.
  const double r = 0.003, e = 1.9 * r, rho = 2000;
  const std::vector<ClumpSphere> tet = tetrahedron(r, e);
  const ClumpMassProperties p = clump_mass_properties(tet, rho);
  double v = 4 * sphere_volume(r);
  Matrix3d second = Matrix3d::Zero();  // int x x^T dV about the origin [m^5]
  for (const ClumpSphere& s : tet)
    second += sphere_volume(r) * (s.centre * s.centre.transpose() + r * r / 5 * Matrix3d::Identity());
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t j = i + 1; j < 4; ++j) {
      // Lens along axis u from sphere i: int s^2 dV = i_perp0 - i_axis/2, int y^2 dV = i_axis/2.
      const Vector3d u = (tet[j].centre - tet[i].centre).normalized();
      const AxialIntegrals m = axial_integrals({{0, r}, {e, r}}, true);
      const Vector3d c = tet[i].centre, m1 = m.first * u;
      const Matrix3d uu = u * u.transpose();
      const Matrix3d local = (m.i_perp0 - m.i_axis / 2) * uu + m.i_axis / 2 * (Matrix3d::Identity() - uu);
      v -= m.volume;
      second -= local + c * m1.transpose() + m1 * c.transpose() + m.volume * c * c.transpose();
      EXPECT_LT(rel_diff(m.volume, lens_volume(r, r, e)), 1e-12);
    }
  }
  const Matrix3d expected = rho * (second.trace() * Matrix3d::Identity() - second);  // com at origin
  EXPECT_LT(rel_diff(p.volume, v), 1e-9);
  EXPECT_LT(p.centre_of_mass.norm(), 1e-9 * r);
  EXPECT_LT(rel_diff(p.inertia, expected), 1e-9);
  EXPECT_LT(rel_diff(p.principal_moments[0], p.principal_moments[2]), 1e-9);
}

TEST(ClumpGeometry, DeepTetrahedronIsIsotropicAndRotationInvariant) {
  // e = 1.2 r: triple and quadruple overlaps, no closed form. Symmetry of the regular tetrahedron
  // makes the inertia isotropic; a rigid motion must move com and inertia with it.
  const double r = 0.002, rho = 2650;
  const std::vector<ClumpSphere> tet = tetrahedron(r, 1.2 * r);
  const ClumpMassProperties p = clump_mass_properties(tet, rho);
  const Vector3d pm = p.principal_moments;
  EXPECT_LT(rel_diff(pm[0], pm[2]), 1e-9);  // requirement: 1e-4
  EXPECT_LT(p.centre_of_mass.norm(), 1e-9 * r);
  EXPECT_GT(p.volume, 4 * sphere_volume(r) - 6 * lens_volume(r, r, 1.2 * r));  // Bonferroni bound
  EXPECT_GT(p.volume, sphere_volume(r));

  const Matrix3d rot = Eigen::AngleAxisd(0.7, Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Vector3d shift(0.05, -0.01, 0.02);
  std::vector<ClumpSphere> moved;
  for (const ClumpSphere& s : tet) moved.push_back({rot * s.centre + shift, s.radius});
  const ClumpMassProperties q = clump_mass_properties(moved, rho);
  EXPECT_LT(rel_diff(q.volume, p.volume), 1e-9);
  EXPECT_LT(rel_diff(q.principal_moments, p.principal_moments), 1e-9);  // requirement: 1e-6
  EXPECT_LT((q.centre_of_mass - (rot * p.centre_of_mass + shift)).norm(), 1e-9 * r);
  EXPECT_LT(rel_diff(q.inertia, Matrix3d(rot * p.inertia * rot.transpose())), 1e-9);
}

TEST(ClumpGeometry, SkewClumpIsRotationInvariant) {
  // Three unequal overlapping spheres, no symmetry: all three moments distinct.
  const std::vector<ClumpSphere> skew = {
      {Vector3d(0, 0, 0), 1.0}, {Vector3d(1.2, 0.3, 0), 0.7}, {Vector3d(0.2, 1.0, 0.6), 0.8}};
  const ClumpMassProperties p = clump_mass_properties(skew, 1.0);
  const Matrix3d rot = Eigen::AngleAxisd(2.1, Vector3d(0.3, 0.9, -0.4).normalized()).toRotationMatrix();
  std::vector<ClumpSphere> moved;
  for (const ClumpSphere& s : skew) moved.push_back({rot * s.centre + Vector3d(3, 1, -2), s.radius});
  const ClumpMassProperties q = clump_mass_properties(moved, 1.0);
  EXPECT_LT(rel_diff(q.volume, p.volume), 1e-9);
  EXPECT_LT(rel_diff(q.principal_moments, p.principal_moments), 1e-9);
  EXPECT_LT(rel_diff(q.inertia, Matrix3d(rot * p.inertia * rot.transpose())), 1e-9);
  for (int k = 0; k < 3; ++k) EXPECT_GT(std::abs(q.principal_axes.col(k).dot(rot * p.principal_axes.col(k))), 1 - 1e-8);
}

TEST(ClumpGeometry, PrincipalAxesOfElongatedClump) {
  // Four overlapping spheres along u: the smallest moment's axis is u; the frame is orthonormal,
  // right-handed, and diagonalises the inertia.
  const Vector3d u = Vector3d(1, 2, -2) / 3, o(0.4, -0.1, 0.2);
  std::vector<ClumpSphere> rod;
  for (int k = 0; k < 4; ++k) rod.push_back({o + 0.8 * k * u, k == 1 ? 0.6 : 0.5});
  const ClumpMassProperties p = clump_mass_properties(rod, 1500.0);
  const Matrix3d& a = p.principal_axes;
  EXPECT_GT(std::abs(a.col(0).dot(u)), 1 - 1e-12);
  EXPECT_LT(p.principal_moments[0], 0.5 * p.principal_moments[1]);
  EXPECT_LE(p.principal_moments[1], p.principal_moments[2]);
  EXPECT_LT((a.transpose() * a - Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(a.determinant(), 1.0, 1e-12);
  EXPECT_LT(rel_diff(a.transpose() * p.inertia * a, p.principal_moments.asDiagonal().toDenseMatrix()), 1e-12);
}

TEST(ClumpGeometry, EnclosedAndDuplicateSpheresCountOnce) {
  const double r = 0.01, rho = 1000;
  const std::vector<ClumpSphere> nested = {
      {Vector3d(0.1, 0, 0), r}, {Vector3d(0.1 + 0.4 * r, 0.2 * r, 0), 0.5 * r}, {Vector3d(0.1, 0, 0), r}};
  const ClumpMassProperties p = clump_mass_properties(nested, rho);
  EXPECT_LT(rel_diff(p.volume, sphere_volume(r)), 1e-12);
  EXPECT_LT((p.centre_of_mass - Vector3d(0.1, 0, 0)).norm(), 1e-12 * r);
  EXPECT_LT(rel_diff(p.inertia, 0.4 * rho * sphere_volume(r) * r * r * Matrix3d::Identity()), 1e-12);
  EXPECT_LT(rel_diff(p.bounding_radius, r), 1e-12);
}

TEST(ClumpGeometry, RejectsBadInput) {
  const std::vector<ClumpSphere> none;
  const std::vector<ClumpSphere> flat = {{Vector3d::Zero(), 0.0}};
  const std::vector<ClumpSphere> ok = {{Vector3d::Zero(), 1.0}};
  EXPECT_THROW(clump_mass_properties(none, 1.0), std::invalid_argument);
  EXPECT_THROW(clump_mass_properties(flat, 1.0), std::invalid_argument);
  EXPECT_THROW(clump_mass_properties(ok, 0.0), std::invalid_argument);
  EXPECT_THROW(clump_mass_properties(ok, std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace dem
