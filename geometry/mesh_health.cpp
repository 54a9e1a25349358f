// Mesh health check and safe repair with CGAL Polygon Mesh Processing (CGAL 5.5, header-only).
// This is the only file that includes CGAL: its templates take most of the library's compile time.
//
// The mesh is worked on as a polygon soup, not a CGAL::Surface_mesh: a halfedge mesh cannot hold
// the non-manifold edges CAD exports often have, and the soup keeps the caller's vertex indices.
// Order: validity -> join duplicate points -> degenerate -> duplicate triangles -> edges (borders,
// non-manifold) -> orientation -> self-intersections -> sizes -> units -> compact.
#include "mesh_health.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/box_intersection_d.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <utility>

namespace dem::geometry {
namespace {

// Exact predicates on double coordinates: collinear / coplanar / do_intersect never lie.
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = std::array<std::int32_t, 3>;
using Soup = std::vector<std::array<std::size_t, 3>>;  // CGAL's polygon soup: indices into points

constexpr std::size_t kMaxExamples = 10;
constexpr double kCoarseTriangle = 50.0;     // [-] longest edge above 50 d: coarse for wear maps
constexpr double kFineTriangle = 50.0;       // [-] longest edge below d / 50: finer than contact needs
constexpr double kLargestPlausible = 100.0;  // [m] bounding box diagonal above: probably millimetres
constexpr double kSmallestPlausible = 1e-3;  // [m] bounding box diagonal below: probably scaled twice

/// The mesh while it is repaired; every triangle remembers its index in the caller's mesh.
struct Work {
  std::vector<Point> points;
  std::vector<Triangle> triangles;
  std::vector<std::int32_t> original;  // (n_triangles) index in the input mesh

  /// Removes the triangles marked in `remove_triangle`; returns their input indices.
  std::vector<std::int32_t> remove(const std::vector<bool>& remove_triangle) {
    std::vector<std::int32_t> removed;
    std::size_t kept = 0;
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      if (remove_triangle[t]) {
        removed.push_back(original[t]);
        continue;
      }
      triangles[kept] = triangles[t];
      original[kept++] = original[t];
    }
    triangles.resize(kept);
    original.resize(kept);
    return removed;
  }
};

/// "1 triangle", "2 triangles": a count with its noun in the right number.
std::string counted(std::int64_t n, const char* singular, const char* plural = nullptr) {
  return fmt::format("{} {}", n,
                     n == 1   ? std::string(singular)
                     : plural ? std::string(plural)
                              : std::string(singular) + "s");
}

/// Appends an issue whose examples are the lowest kMaxExamples of `triangles` (input indices).
void add_issue(MeshReport& report, MeshIssue::Severity severity, std::string what, std::int64_t count,
               std::vector<std::int32_t> triangles) {
  std::sort(triangles.begin(), triangles.end());
  triangles.erase(std::unique(triangles.begin(), triangles.end()), triangles.end());
  MeshIssue issue{severity, std::move(what), count, {}};
  issue.triangles.assign(triangles.begin(), triangles.begin() + std::min(triangles.size(), kMaxExamples));
  report.issues.push_back(std::move(issue));
}

/// One use of an undirected edge by a triangle; `forward` when the triangle runs low -> high index.
struct EdgeUse {
  std::uint64_t key;  // (low vertex << 32) | high vertex
  std::int32_t triangle;
  bool forward;
};

/// Every triangle's three edges, sorted so that the uses of one edge are adjacent.
std::vector<EdgeUse> edge_uses(const std::vector<Triangle>& triangles) {
  std::vector<EdgeUse> uses;
  uses.reserve(3 * triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const auto a = std::uint32_t(triangles[t][k]), b = std::uint32_t(triangles[t][(k + 1) % 3]);
      const std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      uses.push_back({key, std::int32_t(t), a < b});
    }
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& x, const EdgeUse& y) {
    return std::tie(x.key, x.triangle) < std::tie(y.key, y.triangle);
  });
  return uses;
}

/// Calls visit(first, last) for each run of uses of one edge.
template <class Visit>
void for_each_edge(const std::vector<EdgeUse>& uses, Visit visit) {
  for (std::size_t first = 0, last = 0; first < uses.size(); first = last) {
    while (last < uses.size() && uses[last].key == uses[first].key) ++last;
    visit(first, last);
  }
}

/// Disjoint sets with path halving.
struct UnionFind {
  std::vector<std::int32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::int32_t find(std::int32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(std::int32_t a, std::int32_t b) { parent[find(a)] = find(b); }
};

/// Whether the triangles sharing a vertex or an edge still intersect elsewhere, else whether they
/// intersect at all. Same tests as CGAL::Polygon_mesh_processing::internal::do_faces_intersect
/// (CGAL 5.5 self_intersections.h), on the soup's shared indices instead of halfedges.
bool triangles_intersect(const std::vector<Point>& points, const Triangle& s, const Triangle& t) {
  int shared = 0, s_at = -1, t_at = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (s[i] == t[j]) {
        ++shared;
        s_at = i;
        t_at = j;
      }
  const auto p = [&](const Triangle& tri, int corner) -> const Point& { return points[tri[(corner + 3) % 3]]; };
  if (shared == 2) {
    // Shared edge: they overlap only if coplanar with the far corners on the same side of it.
    int s_far = 0, t_far = 0;
    while (s[s_far] == t[0] || s[s_far] == t[1] || s[s_far] == t[2]) ++s_far;
    while (t[t_far] == s[0] || t[t_far] == s[1] || t[t_far] == s[2]) ++t_far;
    const Point &a = p(s, s_far + 1), &b = p(s, s_far + 2), &c = p(s, s_far), &d = p(t, t_far);
    return CGAL::coplanar(a, b, c, d) && CGAL::coplanar_orientation(a, b, c, d) == CGAL::POSITIVE;
  }
  const Kernel::Triangle_3 s_triangle(p(s, 0), p(s, 1), p(s, 2)), t_triangle(p(t, 0), p(t, 1), p(t, 2));
  if (shared == 1) {
    // Shared corner: they meet elsewhere only if an opposite side enters the other triangle.
    return CGAL::do_intersect(s_triangle, Kernel::Segment_3(p(t, t_at + 1), p(t, t_at + 2))) ||
           CGAL::do_intersect(t_triangle, Kernel::Segment_3(p(s, s_at + 1), p(s, s_at + 2)));
  }
  return shared == 0 && CGAL::do_intersect(s_triangle, t_triangle);
}

/// Signed volume enclosed by the triangles `members` (divergence theorem, sum of tetrahedra
/// from the first corner) [m^3]; positive when they face outward.
double signed_volume(const std::vector<Point>& points, const std::vector<Triangle>& triangles,
                     const std::vector<std::int32_t>& members) {
  const Point& origin = points[triangles[members.front()][0]];
  double six_volume = 0;
  for (std::int32_t t : members) {
    const auto& [a, b, c] = triangles[t];
    six_volume += CGAL::scalar_product(points[a] - origin, CGAL::cross_product(points[b] - origin, points[c] - origin));
  }
  return six_volume / 6;
}

/// Whether `a` lists the same corners as `b` in the same cyclic order (same orientation).
bool same_cycle(const Triangle& a, const Triangle& b) {
  return a == b || a == Triangle{b[1], b[2], b[0]} || a == Triangle{b[2], b[0], b[1]};
}

using Severity = MeshIssue::Severity;

/// Counts over the distinct edges, shared by the phases from the edge check to the final measures.
struct EdgeCensus {
  std::vector<EdgeUse> uses;            // of the triangles as oriented once check_orientable has run
  std::vector<bool> on_open_edge;       // (n_triangles) touches a border or non-manifold edge
  std::int64_t border_edges = 0;        // used by one triangle
  std::int64_t non_manifold_edges = 0;  // used by more than two triangles
  std::int64_t disagreeing = 0;         // manifold edges whose two triangles face opposite ways
};

/// The caller's triangles, each remembering its own index; no points yet.
Work start_work(const TriangleMesh& mesh) {
  Work work;
  work.triangles = mesh.triangles;
  work.original.resize(mesh.triangles.size());
  std::iota(work.original.begin(), work.original.end(), 0);
  return work;
}

/// Indices outside the vertex array: the triangle cannot be drawn at all.
void remove_out_of_range(const TriangleMesh& mesh, Work& work, MeshReport& report) {
  const auto n_vertices = std::int64_t(mesh.vertices.size());
  std::vector<bool> out_of_range(work.triangles.size(), false);
  for (std::size_t t = 0; t < work.triangles.size(); ++t)
    for (std::int32_t v : work.triangles[t]) out_of_range[t] = out_of_range[t] || v < 0 || v >= n_vertices;
  if (const auto removed = work.remove(out_of_range); !removed.empty())
    add_issue(report, Severity::warning,
              fmt::format("{} referred to vertices that do not exist; removed",
                          counted(std::int64_t(removed.size()), "triangle")),
              std::int64_t(removed.size()), removed);
}

/// Non-finite coordinates poison every predicate below: fatal, and nothing else is checked.
/// Returns true (with the report finished) when a triangle uses such a vertex.
bool stop_if_non_finite(const TriangleMesh& mesh, const Work& work, MeshReport& report) {
  std::vector<std::int32_t> touching_non_finite;
  std::int64_t non_finite = 0;
  std::vector<bool> vertex_bad(mesh.vertices.size(), false);
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const auto& x = mesh.vertices[v];
    vertex_bad[v] = !(std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]));
  }
  for (std::size_t t = 0; t < work.triangles.size(); ++t) {
    const auto& tri = work.triangles[t];
    if (vertex_bad[tri[0]] || vertex_bad[tri[1]] || vertex_bad[tri[2]]) touching_non_finite.push_back(work.original[t]);
  }
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) non_finite += vertex_bad[v];
  if (touching_non_finite.empty()) return false;
  add_issue(report, Severity::fatal,
            fmt::format("{} with non-finite coordinates (NaN or infinity), used by {}",
                        counted(non_finite, "vertex", "vertices"),
                        counted(std::int64_t(touching_non_finite.size()), "triangle")),
            non_finite, touching_non_finite);
  report.triangles_out = mesh.triangles.size();
  report.vertices_out = mesh.vertices.size();
  return true;
}

/// Points at identical positions become one vertex
/// (CGAL::Polygon_mesh_processing::merge_duplicate_points_in_polygon_soup).
void join_duplicate_points(const TriangleMesh& mesh, Work& work, MeshReport& report) {
  work.points.reserve(mesh.vertices.size());
  for (const auto& x : mesh.vertices) work.points.emplace_back(x[0], x[1], x[2]);
  Soup soup(work.triangles.size());
  for (std::size_t t = 0; t < soup.size(); ++t)
    for (int k = 0; k < 3; ++k) soup[t][k] = std::size_t(work.triangles[t][k]);
  const std::size_t merged = CGAL::Polygon_mesh_processing::merge_duplicate_points_in_polygon_soup(work.points, soup);
  for (std::size_t t = 0; t < soup.size(); ++t)
    for (int k = 0; k < 3; ++k) work.triangles[t][k] = std::int32_t(soup[t][k]);
  if (merged > 0)
    add_issue(report, Severity::repaired,
              fmt::format("{} at identical positions joined", counted(std::int64_t(merged), "vertex", "vertices")),
              std::int64_t(merged), {});
}

/// Degenerate triangles: a repeated vertex, or three collinear points (CGAL::collinear, exact).
void remove_degenerate(Work& work, MeshReport& report) {
  std::vector<bool> degenerate(work.triangles.size(), false);
  for (std::size_t t = 0; t < work.triangles.size(); ++t) {
    const auto& [a, b, c] = work.triangles[t];
    degenerate[t] = a == b || b == c || a == c || CGAL::collinear(work.points[a], work.points[b], work.points[c]);
  }
  if (const auto removed = work.remove(degenerate); !removed.empty())
    add_issue(report, Severity::repaired,
              fmt::format("{} removed (zero area: repeated or collinear vertices)",
                          counted(std::int64_t(removed.size()), "degenerate triangle")),
              std::int64_t(removed.size()), removed);
}

/// Duplicate triangles: the same three vertices in any order; the first one is kept.
void remove_duplicates(Work& work, MeshReport& report) {
  std::vector<std::pair<Triangle, std::int32_t>> sorted(work.triangles.size());
  for (std::size_t t = 0; t < sorted.size(); ++t) {
    sorted[t] = {work.triangles[t], std::int32_t(t)};
    std::sort(sorted[t].first.begin(), sorted[t].first.end());
  }
  std::sort(sorted.begin(), sorted.end());
  std::vector<bool> duplicate(work.triangles.size(), false);
  for (std::size_t k = 1; k < sorted.size(); ++k)
    duplicate[sorted[k].second] = sorted[k].first == sorted[k - 1].first;
  if (const auto removed = work.remove(duplicate); !removed.empty())
    add_issue(report, Severity::repaired,
              fmt::format("{} removed (same three vertices as another triangle)",
                          counted(std::int64_t(removed.size()), "duplicate triangle")),
              std::int64_t(removed.size()), removed);
}

/// Nothing left to be a wall: fatal, and the mesh is emptied. Returns true (with the report
/// finished) when no triangle is left.
bool stop_if_empty(TriangleMesh& mesh, const Work& work, MeshReport& report) {
  if (!work.triangles.empty()) return false;
  add_issue(report, Severity::fatal,
            fmt::format("no triangles left after repair (all {} were invalid, degenerate or duplicates)",
                        report.triangles_in),
            0, {});
  mesh.vertices.clear();
  mesh.triangles.clear();
  return true;
}

/// Edges: a border edge has one triangle, a manifold edge two, a non-manifold edge more.
/// Reports the non-manifold edges and the open border loops.
EdgeCensus check_edges(const Work& work, MeshReport& report) {
  const std::size_t n_triangles = work.triangles.size();
  EdgeCensus edges;
  edges.uses = edge_uses(work.triangles);
  edges.on_open_edge.assign(n_triangles, false);
  const std::vector<EdgeUse>& uses = edges.uses;
  std::vector<std::int32_t> border_triangles, non_manifold_triangles;
  UnionFind border_vertices(work.points.size());
  for_each_edge(uses, [&](std::size_t first, std::size_t last) {
    if (last - first == 2) return;
    for (std::size_t u = first; u < last; ++u) edges.on_open_edge[uses[u].triangle] = true;
    if (last - first == 1) {
      ++edges.border_edges;
      border_vertices.join(std::int32_t(uses[first].key >> 32), std::int32_t(uses[first].key & 0xffffffffu));
      border_triangles.push_back(work.original[uses[first].triangle]);
    } else {
      ++edges.non_manifold_edges;
      for (std::size_t u = first; u < last; ++u) non_manifold_triangles.push_back(work.original[uses[u].triangle]);
    }
  });
  if (edges.non_manifold_edges > 0)
    add_issue(report, Severity::warning,
              fmt::format("{} (shared by more than two triangles): contact works, but the surface "
                          "has no single inside there; check for internal walls or touching parts",
                          counted(edges.non_manifold_edges, "non-manifold edge")),
              edges.non_manifold_edges, non_manifold_triangles);
  // Border loops: connected sets of border edges (loops touching at one vertex count as one).
  if (edges.border_edges > 0) {
    std::vector<std::int32_t> roots;
    for_each_edge(uses, [&](std::size_t first, std::size_t last) {
      if (last - first == 1) roots.push_back(border_vertices.find(std::int32_t(uses[first].key >> 32)));
    });
    std::sort(roots.begin(), roots.end());
    const auto loops = std::int64_t(std::unique(roots.begin(), roots.end()) - roots.begin());
    add_issue(report, Severity::info,
              fmt::format("{} ({}); normal for chutes and plates, a leak only for a "
                          "closed container",
                          counted(loops, "open border loop"), counted(edges.border_edges, "border edge")),
              loops, border_triangles);
  }
  return edges;
}

/// Consistent orientation within each manifold patch (CGAL::Polygon_mesh_processing::orient_polygon_soup,
/// Gueziec et al. 2001); points it duplicates to cut non-manifold vertices are mapped back after.
std::vector<Triangle> orient_with_cgal(const Work& work) {
  const std::size_t n_triangles = work.triangles.size();
  std::vector<Triangle> oriented(n_triangles);
  std::vector<Point> points = work.points;
  Soup soup(n_triangles);
  for (std::size_t t = 0; t < n_triangles; ++t)
    for (int k = 0; k < 3; ++k) soup[t][k] = std::size_t(work.triangles[t][k]);
  CGAL::Polygon_mesh_processing::orient_polygon_soup(points, soup);
  std::map<Point, std::int32_t> index_of;  // only needed when points were duplicated
  if (points.size() > work.points.size())
    for (std::size_t v = 0; v < work.points.size(); ++v) index_of.emplace(work.points[v], std::int32_t(v));
  for (std::size_t t = 0; t < n_triangles; ++t)
    for (int k = 0; k < 3; ++k)
      oriented[t][k] = soup[t][k] < work.points.size() ? std::int32_t(soup[t][k]) : index_of.at(points[soup[t][k]]);
  return oriented;
}

/// Patches: triangles joined through manifold edges. A closed patch faces outward (positive
/// volume); an open one keeps the orientation most of its triangles came with.
/// Rejected: CGAL::Polygon_mesh_processing::orient_to_bound_a_volume, which handles nested
/// shells but needs the whole mesh closed; here a shell inside another is also turned outward.
void orient_patches(Work& work, const EdgeCensus& edges, std::vector<Triangle> oriented, MeshReport& report) {
  const std::size_t n_triangles = work.triangles.size();
  const std::vector<EdgeUse>& uses = edges.uses;
  UnionFind patches(n_triangles);
  for_each_edge(uses, [&](std::size_t first, std::size_t last) {
    if (last - first == 2) patches.join(uses[first].triangle, uses[first + 1].triangle);
  });
  // Triangles sorted by patch, then each patch [begin, end) in turn.
  std::vector<std::int32_t> by_patch(n_triangles), roots(n_triangles);
  for (std::size_t t = 0; t < n_triangles; ++t) roots[t] = patches.find(std::int32_t(t));
  std::iota(by_patch.begin(), by_patch.end(), 0);
  std::stable_sort(by_patch.begin(), by_patch.end(),
                   [&](std::int32_t a, std::int32_t b) { return roots[a] < roots[b]; });
  std::vector<std::int32_t> flipped_triangles;
  for (std::size_t begin = 0, end = 0; begin < n_triangles; begin = end) {
    while (end < n_triangles && roots[by_patch[end]] == roots[by_patch[begin]]) ++end;
    const std::vector<std::int32_t> patch(by_patch.begin() + begin, by_patch.begin() + end);
    const bool closed =
        std::none_of(patch.begin(), patch.end(), [&](std::int32_t t) { return edges.on_open_edge[t]; });
    const auto n_flipped = std::count_if(patch.begin(), patch.end(),
                                         [&](std::int32_t t) { return !same_cycle(oriented[t], work.triangles[t]); });
    const bool turn =
        closed ? signed_volume(work.points, oriented, patch) < 0 : 2 * std::size_t(n_flipped) > patch.size();
    // Unflipped triangles keep their exact corner order; flipped ones swap their last two corners.
    for (std::int32_t t : patch) {
      const Triangle& input = work.triangles[t];
      const bool flip = same_cycle(oriented[t], input) == turn;
      oriented[t] = flip ? Triangle{input[0], input[2], input[1]} : input;
      if (flip) flipped_triangles.push_back(work.original[t]);
    }
  }
  std::sort(flipped_triangles.begin(), flipped_triangles.end());
  work.triangles = oriented;
  if (!flipped_triangles.empty())
    add_issue(report, Severity::repaired,
              fmt::format("{} flipped so that neighbours agree in orientation (closed parts facing outward)",
                          counted(std::int64_t(flipped_triangles.size()), "triangle")),
              std::int64_t(flipped_triangles.size()), flipped_triangles);
}

/// Manifold edges whose two triangles still disagree: a non-orientable (Moebius-like) surface.
/// Recounts the edge uses of the oriented triangles first.
void check_orientable(const Work& work, EdgeCensus& edges, MeshReport& report) {
  edges.uses = edge_uses(work.triangles);
  const std::vector<EdgeUse>& uses = edges.uses;
  std::vector<std::int32_t> disagreeing_triangles;
  for_each_edge(uses, [&](std::size_t first, std::size_t last) {
    if (last - first != 2 || uses[first].forward != uses[first + 1].forward) return;
    ++edges.disagreeing;
    disagreeing_triangles.push_back(work.original[uses[first].triangle]);
  });
  if (edges.disagreeing > 0)
    add_issue(report, Severity::warning,
              fmt::format("{} where neighbouring triangles face opposite ways and cannot be reoriented "
                          "(non-orientable surface)",
                          counted(edges.disagreeing, "edge")),
              edges.disagreeing, disagreeing_triangles);
}

/// Self-intersections: candidate pairs from overlapping bounding boxes (CGAL::box_self_intersection_d),
/// then exact tests. Rejected: PMP::self_intersections, which needs a Surface_mesh (no non-manifold
/// edges); CGAL 5.6's triangle_soup_self_intersections is not in Debian bookworm's 5.5.
void check_self_intersections(const Work& work, MeshReport& report) {
  const std::size_t n_triangles = work.triangles.size();
  using Box =
      CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::int32_t, CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;
  std::vector<Box> boxes;
  boxes.reserve(n_triangles);
  for (std::size_t t = 0; t < n_triangles; ++t) {
    const auto& tri = work.triangles[t];
    boxes.emplace_back(work.points[tri[0]].bbox() + work.points[tri[1]].bbox() + work.points[tri[2]].bbox(),
                       std::int32_t(t));
  }
  std::vector<const Box*> box_pointers;
  for (const Box& box : boxes) box_pointers.push_back(&box);
  std::int64_t pairs = 0;
  std::vector<std::int32_t> crossing;
  const auto test = [&](const Box* a, const Box* b) {
    if (!triangles_intersect(work.points, work.triangles[a->info()], work.triangles[b->info()])) return;
    ++pairs;
    if (crossing.size() < 4 * kMaxExamples) {
      crossing.push_back(work.original[a->info()]);
      crossing.push_back(work.original[b->info()]);
    }
  };
  CGAL::box_self_intersection_d<CGAL::Sequential_tag>(box_pointers.begin(), box_pointers.end(), test,
                                                      std::ptrdiff_t(2000));
  std::sort(crossing.begin(), crossing.end());
  crossing.erase(std::unique(crossing.begin(), crossing.end()), crossing.end());
  if (pairs > 0)
    add_issue(report, Severity::warning,
              fmt::format("{} intersecting (self-intersections): particles can be trapped or "
                          "leak where surfaces cross; union the parts or separate them in CAD",
                          counted(pairs, "pair of triangles", "pairs of triangles")),
              pairs, crossing);
}

/// Length of the edge between points `a` and `b` [m].
double edge_length(const std::vector<Point>& points, std::int32_t a, std::int32_t b) {
  return std::sqrt(CGAL::squared_distance(points[a], points[b]));
}

/// Edge lengths over distinct edges: shortest, longest and median.
void measure_edges(const Work& work, const EdgeCensus& edges, MeshReport& report) {
  const std::vector<EdgeUse>& uses = edges.uses;
  std::vector<double> lengths;
  for_each_edge(uses, [&](std::size_t first, std::size_t) {
    lengths.push_back(edge_length(work.points, std::int32_t(uses[first].key >> 32),
                                  std::int32_t(uses[first].key & 0xffffffffu)));
  });
  std::sort(lengths.begin(), lengths.end());
  report.edge_min = lengths.front();
  report.edge_max = lengths.back();
  report.edge_median = lengths[lengths.size() / 2];
}

/// Each triangle's longest edge against the particle size (skipped when the size is unknown).
void check_triangle_sizes(const Work& work, double particle_diameter, MeshReport& report) {
  if (!(particle_diameter > 0)) return;
  const std::size_t n_triangles = work.triangles.size();
  std::vector<std::int32_t> coarse, fine;
  for (std::size_t t = 0; t < n_triangles; ++t) {
    const auto& [a, b, c] = work.triangles[t];
    const double longest =
        std::max({edge_length(work.points, a, b), edge_length(work.points, b, c), edge_length(work.points, c, a)});
    if (longest > kCoarseTriangle * particle_diameter) coarse.push_back(work.original[t]);
    if (longest < particle_diameter / kFineTriangle) fine.push_back(work.original[t]);
  }
  if (!coarse.empty())
    add_issue(report, Severity::info,
              fmt::format("{} with an edge longer than {} particle diameters ({:.4g} m): fine for contact, "
                          "coarse for wear maps",
                          counted(std::int64_t(coarse.size()), "triangle"), kCoarseTriangle,
                          kCoarseTriangle * particle_diameter),
              std::int64_t(coarse.size()), coarse);
  if (!fine.empty())
    add_issue(
        report, Severity::info,
        fmt::format("{} smaller than 1/{} particle diameter (longest edge < {:.4g} m): more "
                    "triangles than contact needs; decimating would speed up the search",
                    counted(std::int64_t(fine.size()), "triangle"), kFineTriangle, particle_diameter / kFineTriangle),
        std::int64_t(fine.size()), fine);
}

/// Compact: keep only the vertices the triangles use, in their original order.
void write_compacted(const Work& work, TriangleMesh& mesh) {
  const std::size_t n_triangles = work.triangles.size();
  std::vector<std::int32_t> new_index(work.points.size(), -1);
  for (const auto& tri : work.triangles)
    for (std::int32_t v : tri) new_index[v] = 0;
  mesh.vertices.clear();
  for (std::size_t v = 0; v < work.points.size(); ++v)
    if (new_index[v] == 0) {
      new_index[v] = std::int32_t(mesh.vertices.size());
      mesh.vertices.push_back({work.points[v].x(), work.points[v].y(), work.points[v].z()});
    }
  mesh.triangles.resize(n_triangles);
  for (std::size_t t = 0; t < n_triangles; ++t)
    for (int k = 0; k < 3; ++k) mesh.triangles[t][k] = new_index[work.triangles[t][k]];
}

/// Measures of the repaired mesh: counts, closedness, bounding box, area.
void measure_repaired(const TriangleMesh& mesh, const Work& work, const EdgeCensus& edges, MeshReport& report) {
  report.triangles_out = mesh.triangles.size();
  report.vertices_out = mesh.vertices.size();
  report.closed = edges.border_edges == 0 && edges.non_manifold_edges == 0 && edges.disagreeing == 0;
  report.bbox_min = report.bbox_max = mesh.vertices.front();
  for (const auto& x : mesh.vertices)
    for (int axis = 0; axis < 3; ++axis) {
      report.bbox_min[axis] = std::min(report.bbox_min[axis], x[axis]);
      report.bbox_max[axis] = std::max(report.bbox_max[axis], x[axis]);
    }
  for (const auto& [a, b, c] : work.triangles)
    report.area += std::sqrt(CGAL::squared_area(work.points[a], work.points[b], work.points[c]));
}

/// Units: a wall is between a millimetre and a hundred metres across.
void check_units(MeshReport& report) {
  const double diagonal = std::hypot(report.bbox_max[0] - report.bbox_min[0], report.bbox_max[1] - report.bbox_min[1],
                                     report.bbox_max[2] - report.bbox_min[2]);  // [m]
  if (diagonal > kLargestPlausible)
    add_issue(report, Severity::warning,
              fmt::format("the mesh is {:.4g} m across; is it in millimetres? set unit_scale: 0.001", diagonal), 1, {});
  if (diagonal < kSmallestPlausible)
    add_issue(
        report, Severity::warning,
        fmt::format("the mesh is {:.4g} m across; is it in metres already? check unit_scale (1 for metres)", diagonal),
        1, {});
}

}  // namespace

MeshReport check_and_repair(TriangleMesh& mesh, double particle_diameter) {
  MeshReport report;
  report.source = mesh.source;
  report.triangles_in = mesh.triangles.size();
  Work work = start_work(mesh);
  remove_out_of_range(mesh, work, report);
  if (stop_if_non_finite(mesh, work, report)) return report;
  join_duplicate_points(mesh, work, report);
  remove_degenerate(work, report);
  remove_duplicates(work, report);
  if (stop_if_empty(mesh, work, report)) return report;
  EdgeCensus edges = check_edges(work, report);
  orient_patches(work, edges, orient_with_cgal(work), report);
  check_orientable(work, edges, report);
  check_self_intersections(work, report);
  measure_edges(work, edges, report);
  check_triangle_sizes(work, particle_diameter, report);
  write_compacted(work, mesh);
  measure_repaired(mesh, work, edges, report);
  check_units(report);
  return report;
}

}  // namespace dem::geometry
