// Mass properties of the union of spheres (a clump template), overlaps counted once.
// Method: lengths are shifted to the r^3-weighted mean centre and scaled by the enclosing radius,
// and the raw moments int dV, int x dV, int x x^T dV of the union are integrated as nested 1-D
// integrals. z (innermost) is exact: the line through (x, y) meets sphere i in an interval; the
// intervals are merged and int 1, z, z^2 dz taken in closed form. y, then x: adaptive
// Gauss-Kronrod 7-15 (QUADPACK qk15; Piessens et al. 1983) between breakpoints at every exposed
// (not inside another sphere) non-smooth point: chord ends of sphere slices (square-root edges),
// crossings of pairwise intersection circles (kinks); for x also sphere extents, circle extremes
// and equator points, crossings of outlines seen along z, triple points. Each panel [a, b] is
// mapped u = a + (b - a)(1 - cos t)/2, t in [0, pi] (Clenshaw-Curtis' cosine substitution), under
// which sqrt(u - a) = sqrt(b - a) sin(t/2) and sqrt(b - u) are smooth, so the rule converges fast;
// panels are bisected until |K15 - G7| is below their width's share of the tolerance.
// Accuracy: tolerance 10^-resolution * 2/5 V_max r_max^2 (largest sphere's moment, a lower bound
// on every principal moment). |K15 - G7| is pessimistic by orders of magnitude: against closed
// forms and independent 1-D integrals (unit tests) the relative error of volume, centre of mass
// and inertia is <= 1e-9 at resolution 3 and <= 1e-11 at the default 6 (1-20 ms, 2-8 spheres).
// Spheres that do not overlap (after dropping spheres inside another) are summed exactly.
#include "bodies/clump_geometry.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

namespace dem {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// Raw moments about the origin: int dV, int x dV, int x x^T dV (normalised units).
struct RawMoments {
  double volume = 0;
  Vector3d first = Vector3d::Zero();
  Matrix3d second = Matrix3d::Zero();
};

// Circle where the surfaces of spheres i and j meet: centre p, in-plane unit axes e1, e2, radius.
struct Circle { Vector3d p, e1, e2; double rho; int i, j; };

// Gauss-Kronrod 7-15 abscissae on [-1, 1] (index 7 is the centre; odd indices are the Gauss nodes),
// Kronrod weights, and Gauss weights of nodes 1, 3, 5, 7 (QUADPACK qk15, Piessens et al. 1983).
constexpr std::array<double, 8> kNodes = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851, 0.864864423359769072789712788640926,
    0.741531185599394439863864773280788, 0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.0};
constexpr std::array<double, 8> kKronrod = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204, 0.104790010322250183839876322541518,
    0.140653259715525918745189590510238, 0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
constexpr std::array<double, 4> kGauss = {
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327};
constexpr int kMaxDepth = 40;

template <std::size_t N>
using Values = std::array<double, N>;

// Adaptive Gauss-Kronrod over the mapped panel t in [t0, t1] of g(t, out) (see integrate_panel).
// A panel is accepted when |K15 - G7| <= tol (its share of the error), or at the roundoff floor
// 50 eps int|g| (QUADPACK's test), or when it spans less than min_du in u = a + w sin^2(t/2),
// where the rounding of u itself dominates; tol is halved per bisection.
template <std::size_t N, class G>
Values<N> adapt(const G& g, double t0, double t1, double tol, int depth, double w, double min_du) {
  const double half = 0.5 * (t1 - t0), mid = 0.5 * (t0 + t1);
  Values<N> kron{}, gauss{}, f{};
  double abs_sum = 0;
  for (int k = 0; k < 8; ++k) {
    for (int side = 0; side < (k == 7 ? 1 : 2); ++side) {
      g(side == 0 ? mid + half * kNodes[k] : mid - half * kNodes[k], f);
      double f_max = 0;
      for (std::size_t n = 0; n < N; ++n) {
        kron[n] += kKronrod[k] * f[n];
        f_max = std::max(f_max, std::abs(f[n]));
        if (k % 2 == 1) gauss[n] += kGauss[k / 2] * f[n];
      }
      abs_sum += kKronrod[k] * f_max;
    }
  }
  double err = 0;
  for (std::size_t n = 0; n < N; ++n) {
    kron[n] *= half;
    err = std::max(err, std::abs(kron[n] - half * gauss[n]));
  }
  const double du = w * std::sin(mid) * std::sin(half);
  const double roundoff = 50 * std::numeric_limits<double>::epsilon() * half * abs_sum;
  if (err <= std::max(tol, roundoff) || du <= min_du || depth >= kMaxDepth) return kron;
  Values<N> sum = adapt<N>(g, t0, mid, 0.5 * tol, depth + 1, w, min_du);
  const Values<N> right = adapt<N>(g, mid, t1, 0.5 * tol, depth + 1, w, min_du);
  for (std::size_t n = 0; n < N; ++n) sum[n] += right[n];
  return sum;
}

// Integral of f over [a, b] through u = a + (b - a) sin^2(t/2), smoothing square-root ends.
template <std::size_t N, class F>
Values<N> integrate_panel(const F& f, double a, double b, double tol, double min_du) {
  const double w = b - a;
  auto g = [&](double t, Values<N>& out) {
    const double s = std::sin(0.5 * t);
    f(a + w * s * s, out);
    const double jacobian = 0.5 * w * std::sin(t);
    for (double& v : out) v *= jacobian;
  };
  return adapt<N>(g, 0.0, std::numbers::pi, tol, 0, w, min_du);
}

// Integral of f over [lo, hi] panel by panel between the breakpoints; tol is shared by width.
template <std::size_t N, class F>
Values<N> integrate_pieces(const F& f, std::vector<double>& breaks, double lo, double hi, double tol) {
  breaks.push_back(hi);
  std::sort(breaks.begin(), breaks.end());
  const double min_width = 1e-13 * (hi - lo);
  Values<N> sum{};
  double a = lo;
  for (double b : breaks) {
    b = std::min(b, hi);
    if (b <= a || (b - a <= min_width && b < hi)) continue;
    const Values<N> part = integrate_panel<N>(f, a, b, tol * (b - a) / (hi - lo), 1e-11 * (hi - lo));
    for (std::size_t n = 0; n < N; ++n) sum[n] += part[n];
    a = b;
  }
  return sum;
}

// Calls emit(q) for the (up to two) points q of circle c whose coordinate k equals v.
template <class Emit>
void circle_points_at(const Circle& c, int k, double v, Emit&& emit) {
  const double a = c.rho * c.e1[k], b = c.rho * c.e2[k];
  const double amp = std::hypot(a, b);
  if (amp <= 1e-14 * c.rho) return;
  const double q = (v - c.p[k]) / amp;
  if (std::abs(q) > 1) return;
  const double phi = std::atan2(b, a), alpha = std::acos(q);
  for (double th : {phi - alpha, phi + alpha}) emit(Vector3d(c.p + c.rho * (std::cos(th) * c.e1 + std::sin(th) * c.e2)));
}

// Nested integration of the union's raw moments (see the file comment).
class UnionIntegrator {
 public:
  UnionIntegrator(std::vector<ClumpSphere> spheres, double tol) : spheres_(std::move(spheres)), tol_(tol) {
    const int n = static_cast<int>(spheres_.size());
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) add_circle(i, j);
  }

  RawMoments integrate() {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const ClumpSphere& s : spheres_) {
      lo = std::min(lo, s.centre.x() - s.radius);
      hi = std::max(hi, s.centre.x() + s.radius);
    }
    std::vector<double> breaks = x_breakpoints();
    tol_slice_ = 0.05 * tol_ / (hi - lo);
    auto f = [&](double x, Values<10>& out) {
      const Values<6> s = slice(x);
      out = {s[0], x * s[0], s[1], s[2], x * x * s[0], s[3], s[4], x * s[1], x * s[2], s[5]};
    };
    const Values<10> v = integrate_pieces<10>(f, breaks, lo, hi, tol_);
    RawMoments m;
    m.volume = v[0];
    m.first = Vector3d(v[1], v[2], v[3]);
    m.second << v[4], v[7], v[8], v[7], v[5], v[9], v[8], v[9], v[6];
    return m;
  }

 private:
  // A sphere cut by the current plane x = const: its slice is a disc at (cy, cz) of radius c.
  struct Slice { double cy, cz, c; };

  void add_circle(int i, int j) {
    const ClumpSphere &a = spheres_[i], &b = spheres_[j];
    const Vector3d d = b.centre - a.centre;
    const double dist = d.norm();
    if (dist >= a.radius + b.radius || dist <= std::abs(a.radius - b.radius)) return;
    const Vector3d n = d / dist;
    const double t = (dist * dist + a.radius * a.radius - b.radius * b.radius) / (2 * dist);
    const double rho2 = (a.radius - t) * (a.radius + t);
    if (rho2 <= 0) return;
    const Vector3d p = a.centre + t * n;
    const double rho = std::sqrt(rho2);
    // Drop a circle wholly inside a third sphere: its farthest point lies at (w.n, |w_perp| + rho).
    for (const ClumpSphere& k : spheres_) {
      const Vector3d w = p - k.centre;
      const double along = w.dot(n), across = (w - along * n).norm() + rho;
      if (along * along + across * across < (1 - 1e-10) * k.radius * k.radius) return;
    }
    const Vector3d e1 = n.unitOrthogonal();
    circles_.push_back({p, e1, n.cross(e1), rho, i, j});
  }

  // A point strictly inside some sphere: features there (kinks, edges) do not show in the union.
  bool hidden(const Vector3d& q) const {
    for (const ClumpSphere& s : spheres_)
      if ((q - s.centre).squaredNorm() < (1 - 1e-10) * s.radius * s.radius) return true;
    return false;
  }

  // x where the slice integral is not smooth, at exposed points only: sphere extents, circle
  // extremes and equator points, crossings of outlines seen along z, triple points.
  std::vector<double> x_breakpoints() const {
    std::vector<double> xs;
    auto emit = [&](const Vector3d& q) {
      if (!hidden(q)) xs.push_back(q.x());
    };
    for (const ClumpSphere& s : spheres_) {
      emit(s.centre - s.radius * Vector3d::UnitX());
      emit(s.centre + s.radius * Vector3d::UnitX());
    }
    for (const Circle& c : circles_) {
      const double reach = std::hypot(c.e1.x(), c.e2.x());
      if (reach > 0) {
        const Vector3d extreme = c.rho / reach * (c.e1.x() * c.e1 + c.e2.x() * c.e2);
        emit(c.p - extreme);
        emit(c.p + extreme);
      }
      circle_points_at(c, 2, spheres_[c.i].centre.z(), emit);
      circle_points_at(c, 2, spheres_[c.j].centre.z(), emit);
    }
    const std::size_t n = spheres_.size();
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j) {
        outline_crossings(spheres_[i], spheres_[j], xs);
        for (std::size_t k = j + 1; k < n; ++k) triple_points(spheres_[i], spheres_[j], spheres_[k], emit);
      }
    }
    return xs;
  }

  // x of the crossings of two spheres' outlines (circles in the xy plane), if both rims show.
  void outline_crossings(const ClumpSphere& a, const ClumpSphere& b, std::vector<double>& xs) const {
    const double dx = b.centre.x() - a.centre.x(), dy = b.centre.y() - a.centre.y();
    const double d = std::hypot(dx, dy);
    if (d >= a.radius + b.radius || d <= std::abs(a.radius - b.radius)) return;
    const double along = (d * d + a.radius * a.radius - b.radius * b.radius) / (2 * d);
    const double h = std::sqrt(std::max(0.0, (a.radius - along) * (a.radius + along)));
    for (double side : {-1.0, 1.0}) {
      const double x = a.centre.x() + (along * dx + side * h * dy) / d;
      const double y = a.centre.y() + (along * dy - side * h * dx) / d;
      if (!hidden(Vector3d(x, y, a.centre.z())) && !hidden(Vector3d(x, y, b.centre.z()))) xs.push_back(x);
    }
  }

  // Points on all three sphere surfaces: radical planes of (a,b) and (a,c) meet in a line.
  template <class Emit>
  static void triple_points(const ClumpSphere& a, const ClumpSphere& b, const ClumpSphere& c, Emit&& emit) {
    const Vector3d db = b.centre - a.centre, dc = c.centre - a.centre;
    const Vector3d dir = db.cross(dc);
    const double dd = dir.squaredNorm();
    if (dd <= 1e-20 * db.squaredNorm() * dc.squaredNorm()) return;
    const Matrix3d m = (Matrix3d() << db.transpose(), dc.transpose(), dir.transpose()).finished();
    const double ra2 = a.radius * a.radius;
    const Vector3d rhs(0.5 * (db.squaredNorm() - b.radius * b.radius + ra2),
                       0.5 * (dc.squaredNorm() - c.radius * c.radius + ra2), 0.0);
    const Vector3d q0 = m.fullPivLu().solve(rhs);
    const double disc = (ra2 - q0.squaredNorm()) / dd;
    if (disc < 0) return;
    const double s = std::sqrt(disc);
    emit(Vector3d(a.centre + q0 + s * dir));
    emit(Vector3d(a.centre + q0 - s * dir));
  }

  // int over y of (L0, y L0, L1, y^2 L0, L2, y L1) at plane x, L_k = int z^k dz over the union.
  Values<6> slice(double x) {
    slices_.clear();
    ybreaks_.clear();
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const ClumpSphere& s : spheres_) {
      const double dx = std::abs(x - s.centre.x());
      const double c2 = (s.radius - dx) * (s.radius + dx);
      if (c2 <= 0) continue;
      const double c = std::sqrt(c2);
      slices_.push_back({s.centre.y(), s.centre.z(), c});
      for (double y : {s.centre.y() - c, s.centre.y() + c})
        if (!hidden(Vector3d(x, y, s.centre.z()))) ybreaks_.push_back(y);
      lo = std::min(lo, s.centre.y() - c);
      hi = std::max(hi, s.centre.y() + c);
    }
    if (slices_.empty()) return {};
    for (const Circle& c : circles_)
      circle_points_at(c, 0, x, [&](const Vector3d& q) {
        if (!hidden(q)) ybreaks_.push_back(q.y());
      });
    auto f = [&](double y, Values<6>& out) {
      double l0 = 0, l1 = 0, l2 = 0;
      column(y, l0, l1, l2);
      out = {l0, y * l0, l1, y * y * l0, l2, y * l1};
    };
    return integrate_pieces<6>(f, ybreaks_, lo, hi, tol_slice_);
  }

  // Exact int z^k dz, k = 0, 1, 2, over the union of the chords of the current slices at y.
  void column(double y, double& l0, double& l1, double& l2) {
    chords_.clear();
    for (const Slice& s : slices_) {
      const double dy = std::abs(y - s.cy);
      const double h2 = (s.c - dy) * (s.c + dy);
      if (h2 <= 0) continue;
      const double h = std::sqrt(h2);
      chords_.emplace_back(s.cz - h, s.cz + h);
    }
    std::sort(chords_.begin(), chords_.end());
    for (std::size_t k = 0; k < chords_.size();) {
      const double zlo = chords_[k].first;
      double zhi = chords_[k].second;
      for (++k; k < chords_.size() && chords_[k].first <= zhi; ++k) zhi = std::max(zhi, chords_[k].second);
      l0 += zhi - zlo;
      l1 += 0.5 * (zhi * zhi - zlo * zlo);
      l2 += (zhi * zhi * zhi - zlo * zlo * zlo) / 3.0;
    }
  }

  std::vector<ClumpSphere> spheres_;
  std::vector<Circle> circles_;
  double tol_;
  double tol_slice_ = 0;
  std::vector<Slice> slices_;
  std::vector<double> ybreaks_;
  std::vector<std::pair<double, double>> chords_;
};

// Exact raw moments of disjoint spheres: V c and V (c c^T + r^2/5 1) per sphere.
RawMoments sum_of_spheres(const std::vector<ClumpSphere>& spheres) {
  RawMoments m;
  for (const ClumpSphere& s : spheres) {
    const double v = 4.0 / 3.0 * std::numbers::pi * s.radius * s.radius * s.radius;
    m.volume += v;
    m.first += v * s.centre;
    m.second += v * (s.centre * s.centre.transpose() + s.radius * s.radius / 5.0 * Matrix3d::Identity());
  }
  return m;
}

void check_input(std::span<const ClumpSphere> spheres, double density) {
  if (spheres.empty()) throw std::invalid_argument("clump_mass_properties: no spheres");
  if (!(density > 0) || !std::isfinite(density))
    throw std::invalid_argument("clump_mass_properties: density must be positive and finite");
  for (const ClumpSphere& s : spheres)
    if (!(s.radius > 0) || !std::isfinite(s.radius) || !s.centre.allFinite())
      throw std::invalid_argument("clump_mass_properties: radius must be positive, all values finite");
}

}  // namespace

ClumpMassProperties clump_mass_properties(std::span<const ClumpSphere> spheres, double density, int resolution) {
  check_input(spheres, density);
  // Normalise: centre on the r^3-weighted mean centre, scale by the enclosing radius L [m].
  Vector3d ref = Vector3d::Zero();
  double weight = 0;
  for (const ClumpSphere& s : spheres) {
    const double w = s.radius * s.radius * s.radius;
    ref += w * s.centre;
    weight += w;
  }
  ref /= weight;
  double scale = 0;
  for (const ClumpSphere& s : spheres) scale = std::max(scale, (s.centre - ref).norm() + s.radius);

  // Drop spheres inside another (of identical spheres keep the first), then test for overlap.
  std::vector<ClumpSphere> kept;
  for (std::size_t j = 0; j < spheres.size(); ++j) {
    bool inside = false;
    for (std::size_t i = 0; i < spheres.size() && !inside; ++i) {
      if (i == j) continue;
      const double d = (spheres[i].centre - spheres[j].centre).norm();
      const bool j_in_i = d + spheres[j].radius <= spheres[i].radius;
      const bool i_in_j = d + spheres[i].radius <= spheres[j].radius;
      inside = j_in_i && (!i_in_j || i < j);
    }
    if (!inside) kept.push_back({(spheres[j].centre - ref) / scale, spheres[j].radius / scale});
  }
  bool overlap = false;
  double r_max = 0;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    r_max = std::max(r_max, kept[i].radius);
    for (std::size_t j = i + 1; j < kept.size(); ++j)
      overlap = overlap || (kept[i].centre - kept[j].centre).norm() < kept[i].radius + kept[j].radius;
  }

  // Error target: 10^-resolution of the largest sphere's moment of inertia, 2/5 V r^2.
  const double v_max = 4.0 / 3.0 * std::numbers::pi * r_max * r_max * r_max;
  const double tol = std::pow(10.0, -std::clamp(resolution, 3, 11)) * 0.4 * v_max * r_max * r_max;
  const RawMoments m = overlap ? UnionIntegrator(kept, tol).integrate() : sum_of_spheres(kept);

  // Central second moments S, inertia tr(S) 1 - S, back to SI units.
  const Vector3d com_n = m.first / m.volume;
  const Matrix3d central = m.second - m.volume * com_n * com_n.transpose();
  const Matrix3d inertia_n = central.trace() * Matrix3d::Identity() - central;
  const double l2 = scale * scale;
  ClumpMassProperties out;
  out.volume = m.volume * l2 * scale;
  out.mass = density * out.volume;
  out.centre_of_mass = ref + scale * com_n;
  out.inertia = density * l2 * l2 * scale * 0.5 * (inertia_n + inertia_n.transpose());

  // Principal frame, ascending; sign fixed so each axis's largest component is positive, det +1.
  const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(out.inertia);
  out.principal_moments = eig.eigenvalues();
  Matrix3d axes = eig.eigenvectors();
  for (int c = 0; c < 2; ++c) {
    Eigen::Index k = 0;
    axes.col(c).cwiseAbs().maxCoeff(&k);
    if (axes(k, c) < 0) axes.col(c) = -axes.col(c);
  }
  axes.col(2) = axes.col(0).cross(axes.col(1));
  out.principal_axes = axes;

  out.bounding_radius = 0;
  for (const ClumpSphere& s : spheres)
    out.bounding_radius = std::max(out.bounding_radius, (s.centre - out.centre_of_mass).norm() + s.radius);
  return out;
}

}  // namespace dem
