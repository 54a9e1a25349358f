#include "core/mesh_contacts.h"

#include "core/balance.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "base/parallel.h"
#include "core/forces.h"

namespace dem {

namespace {

constexpr int kSlots = MeshContacts::kSlots;

/// out = R v (row-major 3x3).
inline void mul(const std::array<double, 9>& r, const double v[3], double out[3]) {
  out[0] = r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
  out[1] = r[3] * v[0] + r[4] * v[1] + r[5] * v[2];
  out[2] = r[6] * v[0] + r[7] * v[1] + r[8] * v[2];
}
/// out = R^T v.
inline void mul_transposed(const std::array<double, 9>& r, const double v[3], double out[3]) {
  out[0] = r[0] * v[0] + r[3] * v[1] + r[6] * v[2];
  out[1] = r[1] * v[0] + r[4] * v[1] + r[7] * v[2];
  out[2] = r[2] * v[0] + r[5] * v[1] + r[8] * v[2];
}
inline void cross(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1], out[1] = a[2] * b[0] - a[0] * b[2], out[2] = a[0] * b[1] - a[1] * b[0];
}

/// A candidate triangle's closest point to the particle centre (mesh frame).
struct Candidate {
  std::int32_t triangle;
  ClosestPoint closest;
};

/// Triangles that touch the feature a closest point lies on: every triangle around its vertices
/// (an edge's two end points, or the vertex), besides its own triangle, until visit returns false.
template <typename Visit>
void touching_triangles(const TriangleSurface& surface, std::int32_t t, Feature f, Visit visit) {
  const int k = static_cast<int>(f);
  std::int32_t vertices[2];
  int count = 0;
  if (f >= Feature::edge0 && f <= Feature::edge2) {
    vertices[count++] = surface.triangles[t][k - 1];
    vertices[count++] = surface.triangles[t][k % 3];
  } else if (f >= Feature::vertex0) {
    vertices[count++] = surface.triangles[t][k - 4];
  }
  for (int q = 0; q < count; ++q)
    for (std::int32_t i = surface.vertex_begin[vertices[q]]; i < surface.vertex_begin[vertices[q] + 1]; ++i)
      if (surface.vertex_triangles[i] != t && !visit(surface.vertex_triangles[i])) return;
}

/// Keeps the candidates that are physical contacts (see mesh.h); returns how many, in place.
int resolve_contacts(const TriangleSurface& surface, std::vector<Candidate>& list, double radius) {
  if (list.size() <= 1) return static_cast<int>(list.size());  // a lone closest point is a contact
  // Each candidate's distance by triangle, for the neighbours' test below: a sphere with a long
  // interaction range (a liquid bridge's rupture distance) has tens of triangles in reach, and a
  // scan of the list for every neighbour of every edge or vertex contact would cost their cube.
  thread_local std::vector<std::pair<std::int32_t, double>> by_triangle;
  by_triangle.clear();
  for (const Candidate& c : list) by_triangle.emplace_back(c.triangle, c.closest.distance2);
  std::sort(by_triangle.begin(), by_triangle.end());
  auto distance2_of = [&](std::int32_t u) {
    const auto it = std::lower_bound(by_triangle.begin(), by_triangle.end(), std::pair<std::int32_t, double>(u, -1e300));
    return it != by_triangle.end() && it->first == u ? it->second : -1.0;  // -1: not a candidate, farther than the reach
  };
  // Faces first, then by distance: where points merge, the face (the exact plane normal) stays.
  std::sort(list.begin(), list.end(), [](const Candidate& a, const Candidate& b) {
    const bool fa = a.closest.feature == Feature::face, fb = b.closest.feature == Feature::face;
    if (fa != fb) return fa;
    if (a.closest.distance2 != b.closest.distance2) return a.closest.distance2 < b.closest.distance2;
    return a.triangle < b.triangle;
  });
  int kept = 0;
  // Points closer than 1e-6 R are one contact; distances equal to round-off are equal.
  const double merge2 = 1e-12 * radius * radius;
  for (size_t k = 0; k < list.size(); ++k) {
    const Candidate c = list[k];
    bool valid = true;
    if (c.closest.feature != Feature::face) {
      touching_triangles(surface, c.triangle, c.closest.feature, [&](std::int32_t u) {
        const double d2 = distance2_of(u);
        if (d2 >= 0 && d2 < c.closest.distance2 * (1.0 - 1e-13)) valid = false;
        return valid;
      });
    }
    for (int q = 0; q < kept && valid; ++q) {
      const double* a = list[q].closest.point;
      const double dx = a[0] - c.closest.point[0], dy = a[1] - c.closest.point[1], dz = a[2] - c.closest.point[2];
      if (dx * dx + dy * dy + dz * dz <= merge2) valid = false;  // the same contact point
    }
    if (valid) list[kept++] = c;
  }
  return kept;
}

/// Per-thread batch of mesh contacts and where each goes.
struct MeshBatch {
  ContactBatch b;
  std::int32_t slot[kBatch];   // p * kSlots + k: the contact's slot in State::mesh_contacts
  std::int32_t result[kBatch]; // candidate_begin[p] + k: where its results go (Workspace::mesh_forces, mesh_slots)
  double lever[kBatch];        // [m]
  double wall_v[kBatch][3];    // [m/s] wall velocity at the contact
  double point[kBatch][3];     // [m] contact point, world
};

/// Evaluates a batch of mesh contacts: each force and torque is added to its particle's totals
/// (the particle's own thread, slot order) and kept per slot for the records and mesh loads.
void flush(const Model& model, MeshBatch& mb, State& s, ContactForces& out, MeshSlotResults& slot_results) {
  ContactBatch& b = mb.b;
  evaluate_effects(model, b);
  // The columns' addresses in locals: the byte stored to `active` may alias anything, and the
  // vectors' data pointers would be loaded again after it for every contact (forces.cpp).
  double *fx_sum = s.fx.data(), *fy_sum = s.fy.data(), *fz_sum = s.fz.data(), *tx = s.tx.data(), *ty = s.ty.data(), *tz = s.tz.data();
  double *out_x = out.fx.data(), *out_y = out.fy.data(), *out_z = out.fz.data();
  std::uint8_t* active = out.active.data();
  double *fn = slot_results.fn.data(), *shear_power = slot_results.shear_power.data(), *wall_power = slot_results.wall_power.data();
  double *px = slot_results.cx.data(), *py = slot_results.cy.data(), *pz = slot_results.cz.data();
  for (int c = 0; c < b.count; ++c) {
    const std::int32_t k = mb.result[c];
    const std::size_t p = static_cast<std::size_t>(mb.slot[c]) / kSlots;
    const double nx = b.nx[c], ny = b.ny[c], nz = b.nz[c];
    const double fx = b.fn[c] * nx + b.ftx[c], fy = b.fn[c] * ny + b.fty[c], fz = b.fn[c] * nz + b.ftz[c];
    out_x[k] = fx, out_y[k] = fy, out_z[k] = fz;
    const double cx = ny * b.ftz[c] - nz * b.fty[c], cy = nz * b.ftx[c] - nx * b.ftz[c], cz = nx * b.fty[c] - ny * b.ftx[c];
    fx_sum[p] += fx, fy_sum[p] += fy, fz_sum[p] += fz;
    tx[p] += -mb.lever[c] * cx + b.mx[c];
    ty[p] += -mb.lever[c] * cy + b.my[c];
    tz[p] += -mb.lever[c] * cz + b.mz[c];
    active[k] = 1;
    fn[k] = b.fn[c];
    shear_power[k] = std::abs(b.ftx[c] * b.vtx[c] + b.fty[c] * b.vty[c] + b.ftz[c] * b.vtz[c]);
    px[k] = mb.point[c][0], py[k] = mb.point[c][1], pz[k] = mb.point[c][2];
    wall_power[k] = fx * mb.wall_v[c][0] + fy * mb.wall_v[c][1] + fz * mb.wall_v[c][2];
  }
  b.count = 0;
}

}  // namespace

void place_meshes(const Model& model, double time, Workspace& work) {
  const size_t n = model.meshes.size();
  work.mesh_time = time;
  work.mesh_rotation.resize(n), work.mesh_translation.resize(n);
  work.mesh_linear.resize(n), work.mesh_angular.resize(n), work.mesh_origin.resize(n);
  for (size_t m = 0; m < n; ++m) {
    const Pose pose = model.meshes[m].motion.pose(time);
    const Eigen::Matrix3d r = pose.rotation.toRotationMatrix();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) work.mesh_rotation[m][3 * i + j] = r(i, j);
    const RigidVelocity v = model.meshes[m].motion.velocity(time);
    for (int a = 0; a < 3; ++a) {
      work.mesh_translation[m][a] = pose.translation[a];
      work.mesh_linear[m][a] = v.linear[a];
      work.mesh_angular[m][a] = v.angular[a];
      work.mesh_origin[m][a] = v.origin[a];
    }
  }
}

double mesh_displacement_since_build(const Model& model, const State& state, double time) {
  double most = 0;
  for (const MeshWall& mesh : model.meshes) {
    // A mesh switched on since the lists were built has no candidates yet: rebuild now.
    if (state.lists_built_time < mesh.active_from && time >= mesh.active_from) return std::numeric_limits<double>::infinity();
    if (!mesh.motion.is_static())
      most = std::max(most, mesh.motion.max_displacement(state.lists_built_time, time, mesh.surface->bounding_radius));
  }
  return most;
}

void find_mesh_candidates(const Model& model, State& s, Workspace& work, double reach) {
  const size_t n = s.owned();  // ghosts touch no wall
  s.candidate_begin.assign(n + 1, 0);
  s.mesh_candidates.clear();
  s.lists_built_time = work.mesh_time;
  if (model.meshes.empty()) return;
  const long nl = static_cast<long>(n);
  fill_rows(nl, nl >= kParallelMin, work.candidate_scratch, s.candidate_begin, s.mesh_candidates,
            [&](long p, std::vector<std::array<std::int32_t, 2>>& out, size_t k) {
              thread_local std::vector<std::int32_t> near;  // the BVH's answer for one mesh
              const double x[3] = {s.x[p], s.y[p], s.z[p]};
              for (size_t m = 0; m < model.meshes.size(); ++m) {
                if (work.mesh_time < model.meshes[m].active_from) continue;  // not a wall yet
                const double d[3] = {x[0] - work.mesh_translation[m][0], x[1] - work.mesh_translation[m][1],
                                     x[2] - work.mesh_translation[m][2]};
                double local[3];
                mul_transposed(work.mesh_rotation[m], d, local);
                near.clear();
                model.meshes[m].bvh->within(local, s.radius[p] + reach, near);
                std::sort(near.begin(), near.end());
                if (out.size() < k + near.size()) out.resize(2 * (k + near.size()));
                for (const std::int32_t t : near) out[k++] = {static_cast<std::int32_t>(m), t};
              }
              return k;
            });
  // The candidates' distances at the build (Workspace::mesh_gap): a rebuild's work, read by the
  // contact pass of every step until the next.
  resize_discarding(work.mesh_gap, s.mesh_candidates.size());
#pragma omp parallel for schedule(static) if (nl >= kParallelMin)
  for (long p = 0; p < nl; ++p) {
    for (std::int32_t q = s.candidate_begin[p]; q < s.candidate_begin[p + 1]; ++q) {
      const std::int32_t m = s.mesh_candidates[q][0];
      const TriangleSurface& surface = *model.meshes[m].surface;
      const double d[3] = {s.x[p] - work.mesh_translation[m][0], s.y[p] - work.mesh_translation[m][1], s.z[p] - work.mesh_translation[m][2]};
      double local[3];
      mul_transposed(work.mesh_rotation[m], d, local);
      const auto& tri = surface.triangles[s.mesh_candidates[q][1]];
      work.mesh_gap[q] = std::sqrt(closest_point_on_triangle(local, surface.vertices[tri[0]].data(), surface.vertices[tri[1]].data(),
                                                             surface.vertices[tri[2]].data())
                                       .distance2);
    }
  }
}

/// One thread's scratch for the mesh contacts: the batch and the contacts of the last step.
struct MeshContactPass::Scratch {
  MeshBatch mb;
  std::vector<Candidate> list;
  std::vector<double> old_history;
  /// [m] How far any mesh point has moved since the lists were built (infinite: a mesh switched
  /// on since; no candidate is skipped by its distance at the build).
  double meshes_moved = 0;
};

void prepare_mesh_contacts(const Model& model, State& s, Workspace& work) {
  if (model.meshes.empty()) return;
  auto& loads = s.mesh_loads;  // summed afresh by sum_mesh_records
  for (auto* c : {&loads.fx, &loads.fy, &loads.fz, &loads.tx, &loads.ty, &loads.tz, &loads.power}) c->assign(model.meshes.size(), 0.0);
  // Results by candidate: contact k of particle p at candidate_begin[p] + k (a particle has no
  // more contacts than candidates), not one row per slot: most particles touch no wall. Written
  // by the pass before they are read, so not filled.
  const size_t results = s.mesh_candidates.size();
  if (work.mesh_forces.fx.size() != results) {
    ContactForces& f = work.mesh_forces;
    for (auto* c : {&f.fx, &f.fy, &f.fz}) resize_discarding(*c, results);
    resize_discarding(f.active, results);
    work.mesh_slots.resize(results);
  }
}

MeshContactPass::MeshContactPass(const Model& model, State& state, Workspace& work)
    : model_(model), s_(state), work_(work), scratch_(std::make_unique<Scratch>()) {
  scratch_->mb.b.count = 0;
  scratch_->old_history.resize(static_cast<size_t>(kSlots) * std::max(model.history_width, 1));
  scratch_->meshes_moved = mesh_displacement_since_build(model, state, work.mesh_time);
}

MeshContactPass::~MeshContactPass() = default;

namespace {

/// Slot p's contacts of the last step (mesh, point, history into old_history); returns how many.
inline int load_last_contacts(const MeshContacts& mc, long p, int width, std::int32_t old_mesh[kSlots], double old_point[kSlots][3],
                              std::vector<double>& old_history) {
  const int old_count = mc.count[p];
  for (int k = 0; k < old_count; ++k) {
    const size_t slot = static_cast<size_t>(p) * kSlots + k;
    old_mesh[k] = mc.mesh[slot];
    old_point[k][0] = mc.px[slot], old_point[k][1] = mc.py[slot], old_point[k][2] = mc.pz[slot];
    if (width) std::memcpy(&old_history[k * width], &mc.history[slot * width], width * sizeof(double));
  }
  return old_count;
}

/// [m] The distance at the build beyond which slot p's candidates cannot touch (infinite: none skipped).
inline double skip_beyond(const State& s, long p, double radius, double range, const double* gaps, double meshes_moved) {
  // Candidates farther from the sphere at the build than its reach plus how far it and the
  // meshes have moved since cannot touch (the distance to a fixed triangle changes by at most
  // the displacement): skipped unread. The margin of 1e-9 keeps rounding from skipping one
  // that the exact test would take.
  double beyond = std::numeric_limits<double>::infinity();
  if (gaps && std::isfinite(meshes_moved)) {
    const double dx = s.x[p] - s.x_built[p], dy = s.y[p] - s.y_built[p], dz = s.z[p] - s.z_built[p];
    beyond = (radius + range + std::sqrt(dx * dx + dy * dy + dz * dz) + meshes_moved) * (1 + 1e-9);
  }
  return beyond;
}

/// Mesh m's candidates from q on into list (closest points within reach of `local`); returns the next mesh's first.
inline std::int32_t closest_in_reach(const State& s, const TriangleSurface& surface, std::int32_t m, std::int32_t q, std::int32_t last,
                                     const double local[3], double radius, double range, const double* gaps, double beyond,
                                     std::vector<Candidate>& list) {
  list.clear();
  const double reach2 = (radius + range) * (radius + range);
  for (; q < last && s.mesh_candidates[q][0] == m; ++q) {
    if (gaps && gaps[q] > beyond) continue;
    const std::int32_t t = s.mesh_candidates[q][1];
    const auto& tri = surface.triangles[t];
    // The plane's distance bounds the triangle's from below: most candidates of a sphere
    // moving over a surface are out of reach of its plane, and cost a dot product.
    const double* v0 = surface.vertices[tri[0]].data();
    const double* normal = surface.normals[t].data();
    const double above = (local[0] - v0[0]) * normal[0] + (local[1] - v0[1]) * normal[1] + (local[2] - v0[2]) * normal[2];
    if (above * above >= reach2) continue;
    const ClosestPoint cp = closest_point_on_triangle(local, v0, surface.vertices[tri[1]].data(), surface.vertices[tri[2]].data());
    if (cp.distance2 < reach2) list.push_back({t, cp});
  }
  return q;
}

/// The velocity and spin of mesh m's surface at a contact point (world) on its triangle t.
[[gnu::always_inline]] inline void wall_motion(const Workspace& work, std::int32_t m, const MeshWall& mesh, const TriangleSurface& surface,
                                               std::int32_t t, const double point[3], double wall_v[3], double wall_w[3]) {
  const auto& rot = work.mesh_rotation[m];
  // Wall velocity at the contact: rigid motion plus the surface's own (belts, pulleys).
  double arm[3] = {point[0] - work.mesh_origin[m][0], point[1] - work.mesh_origin[m][1], point[2] - work.mesh_origin[m][2]};
  cross(work.mesh_angular[m].data(), arm, wall_v);
  for (int a = 0; a < 3; ++a) wall_v[a] += work.mesh_linear[m][a];
  wall_w[0] = work.mesh_angular[m][0], wall_w[1] = work.mesh_angular[m][1], wall_w[2] = work.mesh_angular[m][2];
  const SurfaceVelocitySpec& sv = mesh.surface_velocity;
  if (sv.kind == SurfaceVelocitySpec::Kind::linear) {
    double tri_normal[3];
    mul(rot, surface.normals[t].data(), tri_normal);
    const double along = sv.velocity.x() * tri_normal[0] + sv.velocity.y() * tri_normal[1] + sv.velocity.z() * tri_normal[2];
    for (int a = 0; a < 3; ++a) wall_v[a] += sv.velocity[a] - along * tri_normal[a];
  } else if (sv.kind == SurfaceVelocitySpec::Kind::rotation) {
    const double w[3] = {sv.axis.x() * sv.angular_speed, sv.axis.y() * sv.angular_speed, sv.axis.z() * sv.angular_speed};
    const double r[3] = {point[0] - sv.point.x(), point[1] - sv.point.y(), point[2] - sv.point.z()};
    double v[3];
    cross(w, r, v);
    for (int a = 0; a < 3; ++a) wall_v[a] += v[a], wall_w[a] += w[a];
  }
}

/// The unused contact of the last step on mesh m nearest to `point` (mesh frame) within a radius; -1: none.
[[gnu::always_inline]] inline int continued_contact(int old_count, const std::int32_t old_mesh[kSlots], const double old_point[kSlots][3],
                                                    const bool old_used[kSlots], std::int32_t m, const double point[3], double radius) {
  int match = -1;
  double best = radius * radius;
  for (int o = 0; o < old_count; ++o) {
    if (old_used[o] || old_mesh[o] != m) continue;
    const double dx = old_point[o][0] - point[0], dy = old_point[o][1] - point[1], dz = old_point[o][2] - point[2];
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < best) best = d2, match = o;
  }
  return match;
}

/// Adds the first `kept` of mesh m's contacts with slot p (list) to the batch and the slot's contacts from `count` on; returns the new count.
inline int add_contacts(const Model& model, State& s, Workspace& work, MeshBatch& mb, const std::vector<Candidate>& list, int kept, long p,
                        std::int32_t first, std::int32_t m, const double local[3], double radius, int count, int old_count,
                        const std::int32_t old_mesh[kSlots], const double old_point[kSlots][3], bool old_used[kSlots],
                        std::vector<double>& old_history) {
  const int width = model.history_width;
  MeshContacts& mc = s.mesh_contacts;
  MeshSlotResults& slot_results = work.mesh_slots;
  const MeshWall& mesh = model.meshes[m];
  const TriangleSurface& surface = *mesh.surface;
  const auto& rot = work.mesh_rotation[m];
  for (int k = 0; k < kept && count < kSlots; ++k) {
    const Candidate& c = list[k];
    // Separate meshes meeting at an edge (chute parts) give the same contact twice.
    double world_point[3];
    mul(rot, c.closest.point, world_point);
    bool seen = false;
    for (int e = mb.b.count - count; e < mb.b.count && !seen; ++e) {
      const double dx = mb.point[e][0] - world_point[0] - work.mesh_translation[m][0];
      const double dy = mb.point[e][1] - world_point[1] - work.mesh_translation[m][1];
      const double dz = mb.point[e][2] - world_point[2] - work.mesh_translation[m][2];
      seen = dx * dx + dy * dy + dz * dz <= 1e-12 * radius * radius;
    }
    if (seen) continue;
    const double dist = std::sqrt(c.closest.distance2);
    double normal_local[3];
    if (dist > 1e-12 * radius) {
      for (int a = 0; a < 3; ++a) normal_local[a] = (local[a] - c.closest.point[a]) / dist;
    } else {
      for (int a = 0; a < 3; ++a) normal_local[a] = surface.normals[c.triangle][a];
    }
    double normal[3], point[3];
    mul(rot, normal_local, normal);
    mul(rot, c.closest.point, point);
    for (int a = 0; a < 3; ++a) point[a] += work.mesh_translation[m][a];
    double wall_v[3], wall_w[3];
    wall_motion(work, m, mesh, surface, c.triangle, point, wall_v, wall_w);
    // The same contact as last step: same mesh, nearest point within a radius.
    const size_t slot = static_cast<size_t>(p) * kSlots + count;
    const int match = continued_contact(old_count, old_mesh, old_point, old_used, m, c.closest.point, radius);
    if (width) {
      if (match >= 0) std::memcpy(&mc.history[slot * width], &old_history[match * width], width * sizeof(double));
      else std::fill_n(&mc.history[slot * width], width, 0.0);
    }
    if (match >= 0) old_used[match] = true;
    mc.mesh[slot] = m, mc.triangle[slot] = c.triangle;
    mc.px[slot] = c.closest.point[0], mc.py[slot] = c.closest.point[1], mc.pz[slot] = c.closest.point[2];
    // Geometry and motion for the effects; a wall is flat (infinite radius).
    ContactBatch& b = mb.b;
    const int e = b.count++;
    const double lever = dist;
    const double vix = s.vx[p] - lever * (s.wy[p] * normal[2] - s.wz[p] * normal[1]);
    const double viy = s.vy[p] - lever * (s.wz[p] * normal[0] - s.wx[p] * normal[2]);
    const double viz = s.vz[p] - lever * (s.wx[p] * normal[1] - s.wy[p] * normal[0]);
    const double rx = vix - wall_v[0], ry = viy - wall_v[1], rz = viz - wall_v[2];
    const double vn = rx * normal[0] + ry * normal[1] + rz * normal[2];
    b.nx[e] = normal[0], b.ny[e] = normal[1], b.nz[e] = normal[2];
    b.vn[e] = vn;
    b.vtx[e] = rx - vn * normal[0], b.vty[e] = ry - vn * normal[1], b.vtz[e] = rz - vn * normal[2];
    b.wx[e] = s.wx[p] - wall_w[0], b.wy[e] = s.wy[p] - wall_w[1], b.wz[e] = s.wz[p] - wall_w[2];
    b.pair_type[e] = model.pair_type(s.material[p], mesh.material);
    b.overlap[e] = radius - dist;
    b.radius_i[e] = radius, b.radius_j[e] = 0.0, b.r_eff[e] = radius;
    b.m_eff[e] = 1.0 / s.inv_mass[p];
    b.inertia_eff[e] = 1.4 * radius * radius / s.inv_mass[p];
    b.history[e] = width ? &mc.history[slot * width] : old_history.data();
    const size_t at = static_cast<size_t>(first) + static_cast<size_t>(count);  // results
    mb.slot[e] = static_cast<std::int32_t>(slot);
    mb.result[e] = static_cast<std::int32_t>(at);
    mb.lever[e] = lever;
    for (int a = 0; a < 3; ++a) mb.wall_v[e][a] = wall_v[a], mb.point[e][a] = point[a];
    slot_results.impact_energy[at] = match >= 0 ? -1.0 : 0.5 / s.inv_mass[p] * vn * vn;
    ++count;
  }
  return count;
}

}  // namespace

void MeshContactPass::run(long begin, long end) {
  const Model& model = model_;
  State& s = s_;
  Workspace& work = work_;
  if (model.meshes.empty()) return;
  const int width = model.history_width;
  MeshContacts& mc = s.mesh_contacts;
  const double range = model.interaction_range;
  MeshBatch& mb = scratch_->mb;
  std::vector<Candidate>& list = scratch_->list;
  std::vector<double>& old_history = scratch_->old_history;
  // Only the slots that had candidates or contacts when the lists were indexed (Workspace::mesh_rows).
  const std::vector<std::int32_t>& rows = work.mesh_rows;
  const double* gaps = work.mesh_gap.size() == s.mesh_candidates.size() && s.x_built.size() >= s.owned() ? work.mesh_gap.data() : nullptr;
  for (auto row = std::lower_bound(rows.begin(), rows.end(), begin); row != rows.end() && *row < end; ++row) {
    const long p = *row;
    const std::int32_t first = s.candidate_begin[p], last = s.candidate_begin[p + 1];
    if (first == last && mc.count[p] == 0) continue;
    // The contacts of the last step, to carry their history.
    std::int32_t old_mesh[kSlots];
    double old_point[kSlots][3];
    bool old_used[kSlots] = {};
    const int old_count = load_last_contacts(mc, p, width, old_mesh, old_point, old_history);
    if (mb.b.count + kSlots > kBatch) flush(model, mb, s, work.mesh_forces, work.mesh_slots);
    const double radius = s.radius[p];
    const double beyond = skip_beyond(s, p, radius, range, gaps, scratch_->meshes_moved);
    int count = 0;
    for (std::int32_t q = first; q < last;) {
      const std::int32_t m = s.mesh_candidates[q][0];
      const TriangleSurface& surface = *model.meshes[m].surface;
      const double d[3] = {s.x[p] - work.mesh_translation[m][0], s.y[p] - work.mesh_translation[m][1], s.z[p] - work.mesh_translation[m][2]};
      double local[3];
      mul_transposed(work.mesh_rotation[m], d, local);
      // Closest points of this mesh's candidate triangles within reach.
      q = closest_in_reach(s, surface, m, q, last, local, radius, range, gaps, beyond, list);
      const int kept = resolve_contacts(surface, list, radius);
      count = add_contacts(model, s, work, mb, list, kept, p, first, m, local, radius, count, old_count, old_mesh, old_point, old_used, old_history);
    }
    mc.count[p] = static_cast<std::uint8_t>(count);
  }
  if (mb.b.count) flush(model, mb, s, work.mesh_forces, work.mesh_slots);
}

void sum_mesh_records(const Model& model, State& s, Workspace& work, long begin, long end) {
  if (model.meshes.empty()) return;
  const MeshContacts& mc = s.mesh_contacts;
  const MeshSlotResults& slot_results = work.mesh_slots;
  // Records per triangle and loads per mesh, summed in slot order.
  auto& loads = s.mesh_loads;
  const double dt = model.dt;
  const ContactForces& f = work.mesh_forces;
  const std::vector<std::int32_t>& rows = work.mesh_rows;  // the others have no contacts
  for (auto row = std::lower_bound(rows.begin(), rows.end(), begin); row != rows.end() && *row < end; ++row) {
    const size_t p = static_cast<size_t>(*row);
    for (int k = 0; k < mc.count[p]; ++k) {
      const size_t slot = p * kSlots + k, at = static_cast<size_t>(s.candidate_begin[p]) + static_cast<size_t>(k);
      if (!f.active[at]) continue;
      const std::int32_t m = mc.mesh[slot], t = mc.triangle[slot];
      TriangleRecords& r = s.records[m];
      const bool record = work.mesh_time >= model.output.records_from;
      const double fn = slot_results.fn[at];
      const double ftx = f.fx[at], fty = f.fy[at], ftz = f.fz[at];
      const double total = std::sqrt(ftx * ftx + fty * fty + ftz * ftz);
      if (record) {
        r.normal_impulse[t] += std::max(fn, 0.0) * dt;
        r.shear_impulse[t] += std::sqrt(std::max(total * total - fn * fn, 0.0)) * dt;
        r.shear_work[t] += slot_results.shear_power[at] * dt;
        if (slot_results.impact_energy[at] >= 0) r.impacts[t] += 1.0, r.impact_energy[t] += slot_results.impact_energy[at];
        // The particle's push on the mesh, -F, in the mesh's own frame: R^T (-F).
        const double push[3] = {-ftx, -fty, -ftz};
        double local[3];
        mul_transposed(work.mesh_rotation[m], push, local);
        r.force_impulse_x[t] += local[0] * dt, r.force_impulse_y[t] += local[1] * dt, r.force_impulse_z[t] += local[2] * dt;
      }
      // The particle pushes the mesh with -F; torque about the motion origin; power F . v_wall.
      loads.fx[m] -= ftx, loads.fy[m] -= fty, loads.fz[m] -= ftz;
      const double arm[3] = {slot_results.cx[at] - work.mesh_origin[m][0], slot_results.cy[at] - work.mesh_origin[m][1],
                             slot_results.cz[at] - work.mesh_origin[m][2]};
      const double force_on_mesh[3] = {-ftx, -fty, -ftz};
      double torque[3];
      cross(arm, force_on_mesh, torque);
      loads.tx[m] += torque[0], loads.ty[m] += torque[1], loads.tz[m] += torque[2];
      loads.power[m] += slot_results.wall_power[at];
    }
  }
}


void mesh_contact_forces(const Model& model, State& state, Workspace& work) {
  if (model.meshes.empty()) return;
  prepare_mesh_contacts(model, state, work);
  const long n = static_cast<long>(state.owned());  // ghosts touch no wall
#pragma omp parallel if (n >= kParallelMin)
  {
    MeshContactPass pass(model, state, work);
    for_own_blocks(work, n, [&](long begin, long end) { pass.run(begin, end); });
  }
  sum_mesh_records(model, state, work, 0, n);
  state.mesh_loads.integrate(model.dt);
}

}  // namespace dem
