// Determinism without atomics or per-contact reaction buffers: the slots (spatially sorted) are
// cut into blocks such that every pair (i, j) has j in i's block or the next (Workspace::block).
// A block's thread adds each contact's force to both bodies directly; blocks evaluated at the
// same time touch no common particle when they are all even or all odd, and an odd block waits
// for the even blocks on either side (block_pass; which thread takes which block: balance.h).
// Every particle's sum therefore runs in a fixed order (the pairs and then the plane walls of
// the even block among its own and the one before it, in list order, then those of the odd one)
// that depends on the data only, so the result is bitwise the same for any thread count and
// schedule. Rejected alternatives: atomics or thread-private force arrays (the summation order,
// and so the last bits of every trajectory, would depend on the number of threads); a buffer slot
// per contact summed afterwards (what this engine did first: 48 bytes more per pair each step,
// and slower; bench/results/design_measurements.csv).
//
// Sum per particle: particle pairs and plane walls as above, then meshes, then gravity. The
// closing half kick of the step runs in the pass that adds gravity. Within step() the sums start
// from the zeros the kick-drift pass left (Workspace::loads_cleared: one pass over six columns
// less, faster for spheres in free fall; bench/results/design_measurements.csv).
//
// A contact passes three stages (measured with perf on B1, the gains of each choice in
// bench/results/design_measurements.csv; each change kept the results bitwise the same, except
// the one-division pair geometry, which changed the last bits):
//   1. the list scan (list_contacts): distance of every pair read, from the x, y, z and
//      radius columns (a copy of the four side by side, one cache line per partner, sped the
//      scan while the contact pass was slower; later its pass cost more than it saved, and B1
//      and B2 ran faster without it). Every pair is written to the next batch entry and kept by
//      advancing the count, with no branch on whether it touches: for the pairs of the skin
//      that is a coin toss the branch predictor loses. Most steps read only the near pairs (gap
//      under a margin of 0.05-0.5 skin at the last full scan, adapted below;
//      Workspace::NearPairs): much faster on B1's dense bed and settle, a little on B2 (its
//      spheres cross the margin in a few steps);
//   2. pair_geometry over the whole batch, vectorised (normal, overlap, relative motion, reduced
//      radius, mass and inertia: the square roots and divisions of a contact);
//   3. the effects' kernels over the batch columns (vectorised, effect.h), then the loads worked
//      out (vectorised) and added to both bodies in list order (scalar: the same body can appear
//      twice in a batch).
#include "base/parallel.h"
#include "core/forces.h"

#include "core/balance.h"
#include "core/domain.h"
#include "core/mesh_contacts.h"
#include "core/neighbors.h"
#include "core/verlet.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>
#include <thread>
#include <utility>

namespace dem {

namespace {

/// Per-thread batch plus where each entry goes. Particle pairs and plane-wall contacts share the
/// batch, a block's pairs in list order and then its walls, so what a particle receives is
/// summed in an order fixed by the data alone, whatever the batch boundaries. A batch holds a run
/// of pairs, then a run of walls (the last wall_count entries): each block's batch is flushed at
/// its end.
struct Batch {
  ContactBatch b;
  std::int32_t contact[kBatch];  // index in the pair or wall list
  // Slots as 64-bit integers, so that pair_geometry's loop has no 32-bit column: mixed with
  // doubles those made GCC take 16 contacts an iteration, two registers a quantity, and spill.
  std::int64_t owner[kBatch];    // slot of body i
  std::int64_t other[kBatch];    // slot of body j (pairs)
  double dx[kBatch], dy[kBatch], dz[kBatch], dist2[kBatch];  // [m], [m^2] centre j to centre i (pairs)
  double lever_i[kBatch], lever_j[kBatch];  // [m] centre to contact point
  // What each contact adds (load_terms): force on i [N], torques on i and on j [N m].
  double force[3][kBatch], torque_i[3][kBatch], torque_j[3][kBatch];
  int wall_count = 0;            // plane-wall contacts: the last entries
  /// The ghost pass: the loads on j are appended here (Workspace::ghost_loads), not added.
  std::vector<double>* ghost_loads = nullptr;
};

/// The contact geometry of the batch's particle pairs (its first `pairs` entries) from the
/// distances the list pass found: normal, overlap, levers, relative motion, effective radius,
/// mass and inertia. Gathers the bodies' columns by slot; vectorised (DEM_KERNEL below).
/// kSpin: also the relative spin and the reduced moment of inertia, which only some effects
/// read (EffectSpec::reads_spin; without: two gathers and four stores a contact less, faster on
/// the settle and more on the dense bed; bench/results/design_measurements.csv).
template <bool kSpin>
[[gnu::always_inline]] inline void pair_geometry_loop(const State& s, int n_materials, Batch& batch, int pairs) {
  ContactBatch& b = batch.b;
  const double* radius = s.radius.data();
  const double *inv_mass = s.inv_mass.data(), *inv_inertia = s.inv_inertia.data();
  const double *vx = s.vx.data(), *vy = s.vy.data(), *vz = s.vz.data();
  const double *wx = s.wx.data(), *wy = s.wy.data(), *wz = s.wz.data();
  const std::int32_t* material = s.material.data();
  DEM_VECTOR_LOOP
  for (int c = 0; c < pairs; ++c) {
    const std::int64_t i = batch.owner[c], j = batch.other[c];
    const double ri = radius[i], rj = radius[j];
    const double dist = std::sqrt(batch.dist2[c]);
    // Four reciprocals from one division (the divider is the slow unit here): 1/dist, and those
    // of the sums of radii, inverse masses and inverse moments of inertia.
    // Without spin, sum_ii = 1 (a product by 1 is exact: the other reciprocals are unchanged).
    const double sum_r = ri + rj, sum_m = inv_mass[i] + inv_mass[j], sum_ii = kSpin ? inv_inertia[i] + inv_inertia[j] : 1.0;
    const double dr = dist * sum_r, mi = sum_m * sum_ii;
    const double q = 1.0 / (dr * mi);
    const double inv_dist = q * sum_r * mi, inv_sum_r = q * dist * mi, inv_sum_m = q * dr * sum_ii, inv_sum_ii = q * dr * sum_m;
    const double nx = batch.dx[c] * inv_dist, ny = batch.dy[c] * inv_dist, nz = batch.dz[c] * inv_dist;
    const double overlap = ri + rj - dist;
    const double lever_i = ri - 0.5 * overlap, lever_j = rj - 0.5 * overlap;
    // Contact-point velocities: v_i + w_i x (-lever_i n) and v_j + w_j x (lever_j n).
    const double vix = vx[i] - lever_i * (wy[i] * nz - wz[i] * ny);
    const double viy = vy[i] - lever_i * (wz[i] * nx - wx[i] * nz);
    const double viz = vz[i] - lever_i * (wx[i] * ny - wy[i] * nx);
    const double vjx = vx[j] + lever_j * (wy[j] * nz - wz[j] * ny);
    const double vjy = vy[j] + lever_j * (wz[j] * nx - wx[j] * nz);
    const double vjz = vz[j] + lever_j * (wx[j] * ny - wy[j] * nx);
    const double rx = vix - vjx, ry = viy - vjy, rz = viz - vjz;
    const double vn = rx * nx + ry * ny + rz * nz;
    b.nx[c] = nx, b.ny[c] = ny, b.nz[c] = nz;
    b.vn[c] = vn;
    b.vtx[c] = rx - vn * nx, b.vty[c] = ry - vn * ny, b.vtz[c] = rz - vn * nz;
    if constexpr (kSpin) b.wx[c] = wx[i] - wx[j], b.wy[c] = wy[i] - wy[j], b.wz[c] = wz[i] - wz[j];
    b.overlap[c] = overlap;
    b.radius_i[c] = ri;
    b.radius_j[c] = rj;
    b.r_eff[c] = ri * rj * inv_sum_r;
    b.m_eff[c] = inv_sum_m;
    // Moments of inertia about the contact point, 7/5 m R^2 = 3.5 I for a sphere (I = 2/5 m R^2).
    if constexpr (kSpin) b.inertia_eff[c] = 3.5 * inv_sum_ii;
    batch.lever_i[c] = lever_i;
    batch.lever_j[c] = lever_j;
  }
  for (int c = 0; c < pairs; ++c) b.pair_type[c] = material[batch.owner[c]] * n_materials + material[batch.other[c]];
}

DEM_KERNEL void pair_geometry(const State& s, int n_materials, Batch& batch, int pairs) { pair_geometry_loop<true>(s, n_materials, batch, pairs); }
DEM_KERNEL void pair_geometry_without_spin(const State& s, int n_materials, Batch& batch, int pairs) {
  pair_geometry_loop<false>(s, n_materials, batch, pairs);
}

/// The loads of batch entries [begin, end), vectorised (DEM_KERNEL): the force on i, F = fn n +
/// ft, and the torques of ft about each centre, (-lever n) x ft, plus the rolling torque (on j:
/// minus it).
DEM_KERNEL void load_terms(Batch& batch, int begin, int end) {
  const ContactBatch& b = batch.b;
  DEM_VECTOR_LOOP
  for (int c = begin; c < end; ++c) {
    const double nx = b.nx[c], ny = b.ny[c], nz = b.nz[c];
    const double ftx = b.ftx[c], fty = b.fty[c], ftz = b.ftz[c];
    batch.force[0][c] = b.fn[c] * nx + ftx, batch.force[1][c] = b.fn[c] * ny + fty, batch.force[2][c] = b.fn[c] * nz + ftz;
    const double cx = ny * ftz - nz * fty, cy = nz * ftx - nx * ftz, cz = nx * fty - ny * ftx;  // n x ft
    batch.torque_i[0][c] = -batch.lever_i[c] * cx + b.mx[c];
    batch.torque_i[1][c] = -batch.lever_i[c] * cy + b.my[c];
    batch.torque_i[2][c] = -batch.lever_i[c] * cz + b.mz[c];
    batch.torque_j[0][c] = -batch.lever_j[c] * cx - b.mx[c];
    batch.torque_j[1][c] = -batch.lever_j[c] * cy - b.my[c];
    batch.torque_j[2][c] = -batch.lever_j[c] * cz - b.mz[c];
  }
}

/// Adds the loads of batch entries [begin, end) (load_terms) to the bodies' totals in entry
/// order: of the particle pairs to both bodies (kPairs), else of the plane walls to their
/// spheres; and keeps each contact's force on i. Scalar: a body can appear twice in a batch.
template <bool kPairs, bool kGhostLoads = false>
[[gnu::always_inline]] inline void add_loads(const Batch& batch, State& s, Workspace& work, int begin, int end) {
  // The columns' addresses held in locals: the byte stored to `active` may alias anything, so
  // read through the vectors they would be loaded again after it, a dozen loads a contact.
  double *fx = s.fx.data(), *fy = s.fy.data(), *fz = s.fz.data(), *tx = s.tx.data(), *ty = s.ty.data(), *tz = s.tz.data();
  ContactForces& wf = work.wall_forces;
  PairForces& pf = work.pair_forces;
  std::uint8_t* active = kPairs ? pf.active.data() : wf.active.data();
  double *kept_x = kPairs ? pf.fx.data() : wf.fx.data(), *kept_y = kPairs ? pf.fy.data() : wf.fy.data(),
         *kept_z = kPairs ? pf.fz.data() : wf.fz.data();
  const bool keep_forces = !kPairs || work.keep_pair_forces;
  const auto &force = batch.force, &torque_i = batch.torque_i, &torque_j = batch.torque_j;
  for (int c = begin; c < end; ++c) {
    const std::int32_t k = batch.contact[c];
    const std::int64_t i = batch.owner[c];
    const double f_x = force[0][c], f_y = force[1][c], f_z = force[2][c];
    fx[i] += f_x, fy[i] += f_y, fz[i] += f_z;
    tx[i] += torque_i[0][c], ty[i] += torque_i[1][c], tz[i] += torque_i[2][c];
    if constexpr (kPairs && kGhostLoads) {
      batch.ghost_loads->insert(batch.ghost_loads->end(), {static_cast<double>(batch.other[c]), f_x, f_y, f_z, torque_j[0][c], torque_j[1][c], torque_j[2][c]});
    } else if constexpr (kPairs) {
      const std::int64_t j = batch.other[c];
      fx[j] -= f_x, fy[j] -= f_y, fz[j] -= f_z;
      tx[j] += torque_j[0][c], ty[j] += torque_j[1][c], tz[j] += torque_j[2][c];
    }
    active[k] = 1;
    if (keep_forces) kept_x[k] = f_x, kept_y[k] = f_y, kept_z[k] = f_z;
  }
}

/// Evaluates a full batch: adds each contact's force and torque to both bodies' totals (a wall's
/// to its sphere), in batch order, and keeps the force on i by contact.
void flush(const Model& model, Batch& batch, State& s, Workspace& work) {
  ContactBatch& b = batch.b;
  if (!b.count) return;
  const int width = model.history_width;
  const int pairs = b.count - batch.wall_count;
  for (int c = 0; c < pairs; ++c) b.history[c] = s.pairs.history.data() + static_cast<size_t>(batch.contact[c]) * width;
  (model.spin_inputs ? pair_geometry : pair_geometry_without_spin)(s, model.n_materials(), batch, pairs);
  evaluate_effects(model, b);
  load_terms(batch, 0, b.count);
  if (batch.ghost_loads) add_loads<true, true>(batch, s, work, 0, pairs);
  else add_loads<true>(batch, s, work, 0, pairs);
  add_loads<false>(batch, s, work, pairs, b.count);
  b.count = 0;
  batch.wall_count = 0;
}

/// The outputs the normal stage does not set (effect.h) start at zero; `load` is set after damping.
[[gnu::always_inline]] inline void zero_outputs(ContactBatch& b) {
  for (int c = 0; c < b.count; ++c) {
    b.gamma_n[c] = b.gamma_t[c] = 0.0;
    b.ftx[c] = b.fty[c] = b.ftz[c] = b.mx[c] = b.my[c] = b.mz[c] = b.energy_dissipated[c] = 0.0;
  }
}

[[gnu::always_inline]] inline void set_load(ContactBatch& b) {
  for (int c = 0; c < b.count; ++c) b.load[c] = b.fn[c] > 0.0 ? b.fn[c] : 0.0;
}

/// A listed contact that is not acting: inactive, history cleared. Only a contact that was
/// active can have a history (index_contacts marks carried histories active), so idle pairs of
/// the skin cost one byte read.
void forget(ContactList& list, std::uint8_t& active, size_t k, int width) {
  if (!active) return;
  active = 0;
  std::fill_n(&list.history[k * width], width, 0.0);
}

/// How the contact pass reads the pair list (Workspace::NearPairs):
///   kAll      every listed pair (the pairs with ghosts);
///   kRefresh  every listed pair, and the near pairs and slot i's position written as it goes;
///   kNear     the near pairs only (step() found no free sphere moved margin/2 since).
/// The pairs left out of the near rows cannot touch before the next full scan, and any of them
/// that was active was cleared by that scan, so the three read the same batches.
enum class Scan { kAll, kRefresh, kNear };

/// The entries [begin, end) of the pair list (kAll, kRefresh) or of the near pairs (kNear), with
/// partners j in [lo, hi): owned partners in the parallel block pass, ghosts in a pass of their
/// own (a ghost may touch spheres of several blocks). One loop whatever the owners: a loop per
/// slot ends after one to three pairs, and the branch predictor misses most of those ends.
/// Only finds which pairs act; pair_geometry does the rest for a whole batch. Every pair read is
/// written to the next free entry and kept by advancing the count: whether a skin pair touches
/// is a coin toss to the branch predictor, so the loop does not branch on it.
/// kPeriodic: the model wraps an axis (minimum image); kGhosts: partners outside [lo, hi) are
/// skipped (without ghosts every partner is an owned slot, and the test is left out).
/// kRefresh: the pairs kept as near pairs are written from `next_near` on, which is advanced.
/// The batch holds no wall entries yet (a batch's pairs come first).
template <bool kPeriodic, bool kGhosts, Scan kScan>
void list_contacts(const Model& model, State& s, Workspace& work, Batch& batch, std::int32_t begin, std::int32_t end,
                   std::int32_t lo, std::int32_t hi, std::int32_t& next_near) {
  constexpr bool kFromNear = kScan == Scan::kNear;
  const int width = model.history_width;
  const double range = model.interaction_range;
  const double *px = s.x.data(), *py = s.y.data(), *pz = s.z.data(), *pr = s.radius.data();
  Workspace::NearPairs& near = work.near;
  const std::int32_t *owner = kFromNear ? near.i.data() : s.pairs.i.data(), *partner = kFromNear ? near.j.data() : s.pairs.j.data();
  std::uint8_t* active = work.pair_forces.active.data();
  double* history = s.pairs.history.data();
  // kRefresh: a pair is kept when its gap is under the margin, or either sphere is not free.
  [[maybe_unused]] const std::int32_t *body = s.body.data(), *attached = s.attached.data();
  std::int32_t kept = next_near;
  int c = batch.b.count;
  for (std::int32_t e = begin; e < end; ++e) {
    const std::int32_t i = owner[e], j = partner[e];
    const std::int32_t k = kFromNear ? near.k[e] : e;
    if constexpr (kGhosts)
      if (j < lo || j >= hi) continue;
    double d[3] = {px[i] - px[j], py[i] - py[j], pz[i] - pz[j]};
    if constexpr (kPeriodic) minimum_image(model, d);
    const double dist2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const double reach = pr[i] + pr[j] + range;
    const bool acts = dist2 < reach * reach;
    batch.dx[c] = d[0], batch.dy[c] = d[1], batch.dz[c] = d[2], batch.dist2[c] = dist2;
    batch.contact[c] = k;
    batch.owner[c] = i, batch.other[c] = j;
    if constexpr (kScan == Scan::kRefresh) {
      const double keep_reach = reach + near.margin;
      const bool keep = (dist2 < keep_reach * keep_reach) | (body[i] >= 0) | (attached[i] >= 0) | (body[j] >= 0) | (attached[j] >= 0);
      near.k[kept] = k, near.i[kept] = i, near.j[kept] = j;
      kept += keep;
    }
    if (!acts & (active[k] != 0)) forget(s.pairs, active[k], k, width);  // rare: a contact ends
    // The row evaluate_effects will copy: the rows of the touching pairs, spread over the list's,
    // missed the cache there without the prefetch (bench/results/design_measurements.csv).
    __builtin_prefetch(history + static_cast<size_t>(k) * width, 1);
    c += acts;
    if (c == kBatch) {
      batch.b.count = c;
      flush(model, batch, s, work);
      c = 0;
    }
  }
  next_near = kept;
  batch.b.count = c;
}

/// The plane-wall pairs [begin, end) of the wall list (a block's, in slot order), in one loop.
void wall_contacts(const Model& model, State& s, Workspace& work, Batch& batch, std::int32_t begin, std::int32_t end) {
  const int width = model.history_width;
  const double range = model.interaction_range;
  ContactBatch& b = batch.b;
  const std::int32_t *owner = s.wall_pairs.i.data(), *wall_of = s.wall_pairs.j.data();
  std::uint8_t* active = work.wall_forces.active.data();
  for (std::int32_t k = begin; k < end; ++k) {
    const std::int32_t i = owner[k], w = wall_of[k];
    const PlaneWall& wall = model.planes[w];
    const double at[3] = {s.walls.px[w], s.walls.py[w], s.walls.pz[w]}, x[3] = {s.x[i], s.y[i], s.z[i]};
    double normal[3];
    const double dist = wall.distance(at, x, normal);
    const double nx = normal[0], ny = normal[1], nz = normal[2];
    const double r = s.radius[i];
    const double overlap = r - dist;
    if (overlap <= -range || dist <= 0.0) {
      forget(s.wall_pairs, active[k], k, width);
      continue;
    }
    const int c = b.count;
    // Contact-point velocity of i: v_i + w_i x (-dist n); the wall's surface velocity, its
    // translation and, for a turning surface, spin a x (contact point - point), a the axis.
    double sx = s.walls.vx[w], sy = s.walls.vy[w], sz = s.walls.vz[w];
    if (wall.spin != 0) {
      const double cx = x[0] - dist * nx - at[0], cy = x[1] - dist * ny - at[1], cz = x[2] - dist * nz - at[2];
      const double* a = wall.normal.data();
      sx += wall.spin * (a[1] * cz - a[2] * cy), sy += wall.spin * (a[2] * cx - a[0] * cz), sz += wall.spin * (a[0] * cy - a[1] * cx);
    }
    const double rx = s.vx[i] - dist * (s.wy[i] * nz - s.wz[i] * ny) - sx;
    const double ry = s.vy[i] - dist * (s.wz[i] * nx - s.wx[i] * nz) - sy;
    const double rz = s.vz[i] - dist * (s.wx[i] * ny - s.wy[i] * nx) - sz;
    const double vn = rx * nx + ry * ny + rz * nz;
    b.nx[c] = nx, b.ny[c] = ny, b.nz[c] = nz, b.vn[c] = vn;
    b.vtx[c] = rx - vn * nx, b.vty[c] = ry - vn * ny, b.vtz[c] = rz - vn * nz;
    b.wx[c] = s.wx[i], b.wy[c] = s.wy[i], b.wz[c] = s.wz[i];
    b.pair_type[c] = model.pair_type(s.material[i], wall.material);
    b.overlap[c] = overlap, b.radius_i[c] = r, b.radius_j[c] = 0.0, b.r_eff[c] = r;
    b.m_eff[c] = 1.0 / s.inv_mass[i], b.inertia_eff[c] = 1.4 * r * r / s.inv_mass[i];
    b.history[c] = s.wall_pairs.history.data() + static_cast<size_t>(k) * width;
    batch.lever_i[c] = dist, batch.lever_j[c] = 0.0;  // load_terms works out a torque on j for every entry
    batch.contact[c] = k;
    batch.owner[c] = i;
    ++batch.wall_count;
    if (++b.count == kBatch) flush(model, batch, s, work);
  }
}

/// What is left of a sphere's step once its contacts with other spheres are summed: its mesh
/// contacts, then gravity and the closing half kick. The block pass does it block by block when
/// nothing else is to be added (no pairs with ghosts, no loads returned by other ranks).
struct Finish {
  MeshContactPass* meshes;   ///< this thread's; null without meshes
  double kick;               ///< [s] closing half kick (0: none)
  const DriftLimits* ahead;  ///< then the next step's opening kick and drift (null: no)
  int* moved;                ///< this thread's Moved flags of that drift
};

/// Waits until another thread has stored `value` in `flag` (release), and sees what it wrote.
void wait_until(std::uint32_t& flag, std::uint32_t value) {
  const std::atomic_ref<std::uint32_t> seen(flag);
  for (int spins = 0; seen.load(std::memory_order_acquire) != value; ++spins) {
#if defined(__x86_64__)
    __builtin_ia32_pause();
#endif
    if (spins > 4096) std::this_thread::yield();  // more threads than cores
  }
}

/// Waits until block b's contacts of this pass are summed (Workspace::block_done).
void wait_for_block(Workspace& work, long b) { wait_until(work.block_done[b], work.pass_epoch); }

/// The mesh records and loads of this thread's blocks, summed once every thread before it has
/// summed its own (Workspace::records_turn): the sums run in slot order, as one thread's would,
/// while a thread that finished its contacts early adds its records as the others still
/// compute, from its own cache. Their time counts in the blocks' work (balance.h). Called by
/// every thread of the contact pass's region, after its blocks are finished.
void sum_records_in_turn(const Model& model, State& s, Workspace& work, long n) {
  const int t = omp_get_thread_num();
  const auto [lo, hi] = thread_blocks(work, n, t, omp_get_num_threads());
  wait_until(work.records_turn, static_cast<std::uint32_t>(t));
  for (long b = lo; b < hi; ++b) {
    const auto start = std::chrono::steady_clock::now();
    sum_mesh_records(model, s, work, b * work.block, std::min(n, (b + 1) * work.block));
    add_block_time(work, b, start);
  }
  std::atomic_ref<std::uint32_t>(work.records_turn).store(static_cast<std::uint32_t>(t + 1), std::memory_order_release);
}

/// The contacts of the owned slots, block by block (see the top of this file). Each thread takes
/// its run of blocks (balance.h) and evaluates its even blocks, then its odd ones. An odd block
/// waits only for the even blocks next to it, and those of another thread are evaluated first,
/// so a thread hardly waits, and there is no barrier between the two halves. Called by every
/// thread of a parallel region.
template <bool kPeriodic, bool kGhosts, Scan kScan>
void block_pass(const Model& model, State& s, Workspace& work, Batch& batch, const Finish* finish) {
  const long n = static_cast<long>(s.owned()), block = work.block, blocks = (n + block - 1) / block;
  const auto [lo, hi] = thread_blocks(work, n, omp_get_thread_num(), omp_get_num_threads());
  const std::int32_t owned = static_cast<std::int32_t>(n);
  const auto evaluate = [&](long b) {
    const auto start = std::chrono::steady_clock::now();
    const long first = b * block, last = std::min(n, (b + 1) * block);
    // The block's pairs in one loop, then its plane-wall contacts. (A slot's walls right after
    // its own pairs split the loop at every slot with walls, and the predictor missed its ends:
    // the box's settle and dense bed ran slower that way: bench/results/design_measurements.csv.)
    Workspace::NearPairs& near = work.near;
    std::int32_t kept = work.pair_begin[first];  // the block's run of near pairs
    const std::int32_t to = kScan == Scan::kNear ? near.end[b] : work.pair_begin[last];
    list_contacts<kPeriodic, kGhosts, kScan>(model, s, work, batch, work.pair_begin[first], to, 0, owned, kept);
    if constexpr (kScan == Scan::kRefresh) near.end[b] = kept;
    wall_contacts(model, s, work, batch, work.wall_begin[first], work.wall_begin[last]);
    if constexpr (kScan == Scan::kRefresh)
      for (long i = first; i < last; ++i)
        near.x[i] = static_cast<float>(s.x[i] - s.x_built[i]), near.y[i] = static_cast<float>(s.y[i] - s.y_built[i]),
        near.z[i] = static_cast<float>(s.z[i] - s.z_built[i]);
    flush(model, batch, s, work);
    std::atomic_ref<std::uint32_t>(work.block_done[b]).store(work.pass_epoch, std::memory_order_release);
    add_block_time(work, b, start);
  };
  // A block's spheres have all their pair contacts once it and the block before it are summed:
  // block 0 after itself, an odd block and the one after it after the odd one.
  const auto complete = [&](long b) {
    if (!finish || b >= blocks) return;
    const auto start = std::chrono::steady_clock::now();
    const long first = b * block, last = std::min(n, (b + 1) * block);
    if (finish->meshes) finish->meshes->run(first, last);
    *finish->moved |= gravity_kick_range(model.gravity.data(), s, first, last, finish->kick, finish->ahead, model.dt);
    add_block_time(work, b, start);
  };
  const auto evaluate_odd = [&](long b) { evaluate(b), complete(b), complete(b + 1); };
  // Even blocks first: those at the ends of the run (a neighbour's odd block may wait for them).
  const long first_even = lo + (lo & 1), last_even = (hi - 1) - ((hi - 1) & 1);
  if (first_even < hi) evaluate(first_even);
  if (last_even > first_even) evaluate(last_even);
  for (long b = first_even + 2; b < last_even; b += 2) evaluate(b);
  if (lo == 0 && hi > 0) complete(0);
  // Then the odd ones, those at the ends last (they may wait for a neighbour's even block).
  const long first_odd = lo + 1 - (lo & 1), last_odd = (hi - 1) - 1 + ((hi - 1) & 1);
  for (long b = first_odd + 2; b < last_odd; b += 2) evaluate_odd(b);
  const auto evaluate_edge = [&](long b) {
    if (b - 1 < lo) wait_for_block(work, b - 1);
    if (b + 1 < blocks && b + 1 >= hi) wait_for_block(work, b + 1);
    evaluate_odd(b);
  };
  if (first_odd < hi) evaluate_edge(first_odd);
  if (last_odd > first_odd) evaluate_edge(last_odd);
}

/// The block pass for each case, by [periodic][ghosts].
using BlockPass = void (*)(const Model&, State&, Workspace&, Batch&, const Finish*);
template <Scan kScan>
constexpr BlockPass pass_of[2][2] = {{block_pass<false, false, kScan>, block_pass<false, true, kScan>},
                                  {block_pass<true, false, kScan>, block_pass<true, true, kScan>}};

/// Slots [begin, end): forces and torques set to zero.
DEM_KERNEL void clear_loads(State& s, long begin, long end) {
  double *fx = s.fx.data(), *fy = s.fy.data(), *fz = s.fz.data(), *tx = s.tx.data(), *ty = s.ty.data(), *tz = s.tz.data();
  DEM_VECTOR_LOOP
  for (long p = begin; p < end; ++p) fx[p] = fy[p] = fz[p] = tx[p] = ty[p] = tz[p] = 0.0;
}

}  // namespace

namespace {

/// Each contact's history row into the batch's columns (kIn) or back (!kIn), for a width known
/// when compiled: unrolled, without a loop over the width per contact.
template <int kWidth, bool kIn>
[[gnu::always_inline]] inline void copy_history(ContactBatch& b) {
  for (int c = 0; c < b.count; ++c) {
    double* row = b.history[c];
    for (int q = 0; q < kWidth; ++q) {
      if constexpr (kIn) b.hist[q][c] = row[q];
      else row[q] = b.hist[q][c];
    }
  }
}

template <bool kIn>
[[gnu::always_inline]] inline void copy_histories(ContactBatch& b, int width) {
  static_assert(kHistoryMax == 8);
  switch (width) {
    case 0: return;
    case 1: return copy_history<1, kIn>(b);
    case 2: return copy_history<2, kIn>(b);
    case 3: return copy_history<3, kIn>(b);
    case 4: return copy_history<4, kIn>(b);
    case 5: return copy_history<5, kIn>(b);
    case 6: return copy_history<6, kIn>(b);
    case 7: return copy_history<7, kIn>(b);
    default: return copy_history<8, kIn>(b);
  }
}

}  // namespace

DEM_KERNEL void evaluate_effects(const Model& model, ContactBatch& b) {
  copy_histories<true>(b, model.history_width);
  zero_outputs(b);
  bool load_set = false;
  for (const ActiveEffect& e : model.effects) {
    if (!load_set && e.spec->stage > Stage::damping) set_load(b), load_set = true;
    const EffectContext ctx{model.pair_table.data(), model.pair_stride, e.param_offset, e.history_offset,
                            e.options.data(), model.dt};
    e.spec->kernel(ctx, b);
  }
  if (!load_set) set_load(b);
  copy_histories<false>(b, model.history_width);
}

namespace {

/// Readies the pair list's scan: the near pairs' margin, age and time, and the pair forces kept.
inline void prepare_pair_scan(const Model& model, const State& s, Workspace& work, bool near) {
  if (!near && work.near.valid) {
    // A full scan because spheres moved half the margin: the margin follows the motion, so that
    // the near pairs last 4-16 steps (a rebuild's scan leaves it as it is). Its size changes the
    // speed only: the contacts found are the same.
    Workspace::NearPairs& pairs = work.near;
    if (pairs.age < 4) pairs.margin = std::min(1.5 * pairs.margin, 0.5 * model.skin);
    else if (pairs.age > 16) pairs.margin = std::max(pairs.margin / 1.5, 0.05 * model.skin);
  }
  work.near.age = near ? work.near.age + 1 : 0;
  // A full scan takes the positions at the meshes' time (place_meshes); before the drift ahead's
  // limits, which measure the common drift from it.
  if (!near) work.near.time = work.mesh_time;
  if (work.keep_pair_forces && work.pair_forces.fx.size() != s.pairs.size())  // asked for since the lists were built
    for (auto* c : {&work.pair_forces.fx, &work.pair_forces.fy, &work.pair_forces.fz}) c->assign(s.pairs.size(), 0.0);
}

/// The block pass on every thread (with finish_in_pass, also each block's meshes, gravity and kick); returns the drift ahead's Moved flags.
inline int contact_pass(const Model& model, State& s, Workspace& work, double kick, bool near, bool finish_in_pass, const DriftLimits* ahead) {
  const long n_all = static_cast<long>(s.size());
  const long n = static_cast<long>(s.owned());
  const bool periodic = model.periodic();
  const bool ghosts = n_all > n;
  if (finish_in_pass) prepare_mesh_contacts(model, s, work);  // else mesh_contact_forces does
  share_blocks(work, n);
  work.records_turn = 0;
  int moved = 0;
#pragma omp parallel if (n >= kParallelMin) reduction(| : moved)
  {
    const long clear_from = work.loads_cleared ? n : 0;  // owned slots zeroed by the kick-drift pass
    if (clear_from < n_all) {
#pragma omp for schedule(static)
      for (long begin = clear_from; begin < n_all; begin += kChunk) clear_loads(s, begin, std::min(n_all, begin + kChunk));
    }
    Batch batch;
    std::optional<MeshContactPass> meshes;
    if (finish_in_pass && !model.meshes.empty()) meshes.emplace(model, s, work);
    int thread_moved = 0;
    const Finish finish{meshes ? &*meshes : nullptr, kick, ahead, &thread_moved};
    (near ? pass_of<Scan::kNear> : pass_of<Scan::kRefresh>)[periodic][ghosts](model, s, work, batch, finish_in_pass ? &finish : nullptr);
    if (meshes) sum_records_in_turn(model, s, work, n);
    moved |= thread_moved;
  }
  return moved;
}

/// The pairs with ghosts, after the block pass: loads on owned spheres added as they go, those on ghosts after.
inline void ghost_pairs(const Model& model, State& s, Workspace& work) {
  const long n_all = static_cast<long>(s.size());
  const std::int32_t owned = static_cast<std::int32_t>(s.owned());
  const bool periodic = model.periodic();
  // Pairs with ghosts (the subdomain's faces shared with its upper neighbours), in parallel
  // over their owned spheres: each thread takes a run of them in slot order and adds to its
  // own spheres; the loads on the ghosts, which several threads touch, are kept per contact
  // and added after in pass order, so every sum is the serial one whatever the threads.
  const long owners = static_cast<long>(work.ghost_owners.size());
  const int threads = owners >= work.ghost_pass_parallel_min ? omp_get_max_threads() : 1;
  work.ghost_loads.resize(static_cast<size_t>(threads));
#pragma omp parallel num_threads(threads)
  {
    std::vector<double>& out = work.ghost_loads[static_cast<size_t>(omp_get_thread_num())];
    out.clear();
    Batch batch;
    batch.ghost_loads = &out;
    std::int32_t unused = 0;
#pragma omp for schedule(static)  // contiguous runs in thread order
    for (long e = 0; e < owners; ++e) {
      const std::int32_t i = work.ghost_owners[static_cast<size_t>(e)];
      (periodic ? list_contacts<true, true, Scan::kAll> : list_contacts<false, true, Scan::kAll>)(
          model, s, work, batch, work.pair_begin[i], work.pair_begin[i + 1], owned, static_cast<std::int32_t>(n_all), unused);
    }
    flush(model, batch, s, work);
  }
  double *fx = s.fx.data(), *fy = s.fy.data(), *fz = s.fz.data(), *tx = s.tx.data(), *ty = s.ty.data(), *tz = s.tz.data();
  for (int t = 0; t < threads; ++t) {
    const std::vector<double>& loads = work.ghost_loads[static_cast<size_t>(t)];
    for (size_t k = 0; k < loads.size(); k += 7) {
      const size_t j = static_cast<size_t>(loads[k]);
      fx[j] -= loads[k + 1], fy[j] -= loads[k + 2], fz[j] -= loads[k + 3];
      tx[j] += loads[k + 4], ty[j] += loads[k + 5], tz[j] += loads[k + 6];
    }
  }
}

/// With ghosts or ranks, what the block pass leaves, each a pass of its own: pairs with ghosts, meshes, gravity and kick.
inline void finish_apart(const Model& model, State& s, Workspace& work, double kick) {
  const long n = static_cast<long>(s.owned());
  if (!work.ghost_owners.empty()) ghost_pairs(model, s, work);
  mesh_contact_forces(model, s, work);
  if (work.domain) work.domain->return_ghost_loads(s);
  // Gravity, and the closing half kick of free spheres.
#pragma omp parallel if (n >= kParallelMin)
  for_own_blocks(work, n, [&](long begin, long end) { gravity_kick_range(model.gravity.data(), s, begin, end, kick, nullptr, model.dt); });
}

/// Each body's force and torque from its spheres plus its weight, then (kick != 0) its closing half kick.
inline void body_loads(const Model& model, State& s, const Workspace& work, double kick) {
  // Bodies: force and torque about the centre of mass from their spheres, plus weight.
  const double gx = model.gravity[0], gy = model.gravity[1], gz = model.gravity[2];
  Bodies& bodies = s.bodies;
  const long nb = static_cast<long>(bodies.size());
#pragma omp parallel for schedule(static) if (nb >= kParallelMin)
  for (long b = 0; b < nb; ++b) {
    double fx = bodies.mass[b] * gx, fy = bodies.mass[b] * gy, fz = bodies.mass[b] * gz, tx = 0, ty = 0, tz = 0;
    for (std::int32_t q = work.body_begin[b]; q < work.body_begin[b + 1]; ++q) {
      const std::int32_t p = work.body_members[q];
      const double rx = s.x[p] - bodies.x[b], ry = s.y[p] - bodies.y[b], rz = s.z[p] - bodies.z[b];
      fx += s.fx[p], fy += s.fy[p], fz += s.fz[p];
      tx += s.tx[p] + ry * s.fz[p] - rz * s.fy[p];
      ty += s.ty[p] + rz * s.fx[p] - rx * s.fz[p];
      tz += s.tz[p] + rx * s.fy[p] - ry * s.fx[p];
    }
    bodies.fx[b] = fx, bodies.fy[b] = fy, bodies.fz[b] = fz;
    bodies.tx[b] = tx, bodies.ty[b] = ty, bodies.tz[b] = tz;
    if (kick != 0.0) {
      const double a = kick / bodies.mass[b];
      bodies.vx[b] += a * fx, bodies.vy[b] += a * fy, bodies.vz[b] += a * fz;
      bodies.lx[b] += kick * tx, bodies.ly[b] += kick * ty, bodies.lz[b] += kick * tz;
    }
  }
}

/// The force on each wall: the reaction of its contacts, plus the loads of the spheres glued to it.
inline void wall_loads(const Model& model, State& s, const Workspace& work) {
  const long n = static_cast<long>(s.owned());
  // Force on each wall (reaction of its contacts), summed in list order.
  const ContactForces& wf = work.wall_forces;
  for (auto* column : {&s.walls.fx, &s.walls.fy, &s.walls.fz}) std::fill(column->begin(), column->end(), 0.0);
  if (!model.planes.empty()) {
    double* wfx = s.walls.fx.data();
    double* wfy = s.walls.fy.data();
    double* wfz = s.walls.fz.data();
    const std::int32_t* wall = s.wall_pairs.j.data();
    const size_t count = s.wall_pairs.size();
    for (size_t k = 0; k < count; ++k) {
      if (!wf.active[k]) continue;
      const std::int32_t w = wall[k];
      wfx[w] -= wf.fx[k], wfy[w] -= wf.fy[k], wfz[w] -= wf.fz[k];
    }
    if (work.domain) work.domain->sum_wall_loads(s);
  }
  // Glued spheres pass their contact forces to their wall, summed in slot order.
  if (!model.has_attached) return;
  for (long p = 0; p < n; ++p) {
    const std::int32_t w = s.attached[p];
    if (w < 0) continue;
    s.walls.fx[w] += s.fx[p], s.walls.fy[w] += s.fy[p], s.walls.fz[w] += s.fz[p];
  }
}

}  // namespace

void compute_forces(const Model& model, State& s, Workspace& work, double kick) {
  ForcePass pass;
  pass.kick = kick;
  compute_forces(model, s, work, pass);
}

void compute_forces(const Model& model, State& s, Workspace& work, const ForcePass& pass) {
  const double kick = pass.kick;
  const long n_all = static_cast<long>(s.size());
  const long n = static_cast<long>(s.owned());  // ghosts: forces returned to their owners
  const bool ghosts = n_all > n;  // the block pass skips them: their pairs are evaluated apart
  const bool near = work.near.valid && work.near.trusted;
  prepare_pair_scan(model, s, work, near);
  // Without ghosts the block pass finishes each block's spheres (meshes, gravity, kick) as soon
  // as their pair contacts are summed, while they are in cache: two passes and their barriers less.
  const bool finish_in_pass = !ghosts && !work.domain;
  // The next step's drift tests positions against the lists as they are after this pass.
  const bool ahead = pass.drift_ahead && kick != 0.0 && finish_in_pass;
  // The drift ahead brings the spheres to the next step's time.
  const DriftLimits limits = ahead ? drift_limits(model, s, work, /*near_valid=*/true, s.time + 2.0 * model.dt) : DriftLimits{};
  const int moved = contact_pass(model, s, work, kick, near, finish_in_pass, ahead ? &limits : nullptr);
  if (finish_in_pass && !model.meshes.empty()) s.mesh_loads.integrate(model.dt);  // else mesh_contact_forces does
  work.drifted_ahead = ahead ? (moved | untested(limits)) : -1;
  work.drifts_ahead += ahead;
  work.near.valid = true, work.near.trusted = false, work.loads_cleared = false;
  work.near_refreshes += !near;
  if (!finish_in_pass) finish_apart(model, s, work, kick);
  body_loads(model, s, work, kick);
  wall_loads(model, s, work);
}

}  // namespace dem
